"""Times heyoka (Taylor's method compiled by LLVM) against gearbif on the gear, in one run.

Called by scripts/bench_peers.sh, which builds gearbif and installs heyoka into a local venv.
The workloads (the gear of the paper at Θ = 25°, 1000 drive periods in one integration with a
strobe sample at every period):

  lock_co   f = 2.7 Hz from (β, ω) = (π, 0): co-rotating lock, friction
  lock_ctr  f = 2.7 Hz from (0, 0): counter-rotating lock, friction
  eta0      f = 2.7 Hz from (0, 0), η = 0
  stickslip f = 4.5 Hz from (0, 0): frequent stick/slip events

Every method's error is max(|Δβ|, |Δω|) at the end against one common reference: gearbif's
event-driven DOP853 at tol 1e-14 (printed by `gearbif bench-integrators` as `reference_x`);
heyoka at tol 1e-15 is checked against it and its distance printed in the table's header.

heyoka integrates the same Filippov system: the side s = sgn ω is a runtime parameter, a terminal
event on ω = 0 stops the integration, where Python decides crossing or stick as gearbif does
(|a| ≤ η sticks); a stick phase is not integrated: the release time is solved in closed form
(|g τ(α, β*)| = η) and the integration restarts there. With the state Jacobian, heyoka
propagates its variational equations (`var_ode_sys`), and the saltation matrices are applied at
the events (crossing: the ω row times a₊/a₋; stick: ω row 0; release: identity).

Output: a Markdown table (and CSV) under docs/tables/, with machine, date and commit.
"""

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time

import heyoka as hy
import numpy as np

MU0_4PI = 1.25663706212e-6 / (4.0 * math.pi)
M1 = M2 = 3.51
R = 0.040
INERTIA = 6.45e-5
ZETA = 1.1
ETA = 23.1
G = MU0_4PI * M1 * M2 / R**3 / INERTIA
TH = math.radians(25.0)
DELTA = math.cos(TH) ** 2 - 2.0 * math.sin(TH) ** 2

WORKLOADS = {
    "lock_co": dict(f=2.7, x0=(math.pi, 0.0), eta=ETA),
    "lock_ctr": dict(f=2.7, x0=(0.0, 0.0), eta=ETA),
    "eta0": dict(f=2.7, x0=(0.0, 0.0), eta=0.0),
    "stickslip": dict(f=4.5, x0=(0.0, 0.0), eta=ETA),
}
PERIODS = 1000


def tau(alpha, beta):
    return -math.sin(alpha) * math.cos(beta) + DELTA * math.cos(alpha) * math.sin(beta)


def next_release(f, t, beta, eta):
    """The gear's closed-form release time (as gearbif's Gear::next_release), None if never."""
    nu = 2.0 * math.pi * f
    if G * abs(tau(nu * t, beta)) >= eta:
        return t
    sb, cb = math.sin(beta), math.cos(beta)
    amp = G * math.sqrt(cb * cb + DELTA * DELTA * sb * sb)
    if amp <= eta:
        return None
    phi = math.atan2(DELTA * sb, -cb)
    c = math.asin(eta / amp)
    u0 = nu * t + phi
    k = math.ceil((u0 - c) / math.pi)
    u = c + k * math.pi
    if u < u0:
        u += math.pi
    return t + (u - u0) / nu


class HeyokaGear:
    """A heyoka integrator of the gear with the Filippov event handling done in Python."""

    def __init__(self, f, eta, tol, jacobian):
        beta, omega = hy.make_vars("beta", "omega")
        alpha = 2.0 * math.pi * f * hy.time
        s = hy.par[0]
        rhs = -ZETA * omega - s * eta + G * (
            -hy.sin(alpha) * hy.cos(beta) + DELTA * hy.cos(alpha) * hy.sin(beta))
        sys_ = [(beta, omega), (omega, rhs)]
        self.f, self.eta, self.jac = f, eta, jacobian
        # arrivals on ω = 0 from above (event 0) and from below (event 1); an event of the other
        # direction (a tangential release) is passed over. The cooldown is explicit: heyoka's
        # automatic one scales with 1/|ω̇| and is long after a tangential release, where it hid
        # the next crossing.
        cool = 1e-9 / f
        evs = [hy.t_event(omega, direction=hy.event_direction.negative, cooldown=cool),
               hy.t_event(omega, direction=hy.event_direction.positive, cooldown=cool)]
        # without friction the field is smooth: no events, no parameter (heyoka's best case)
        kw = dict(tol=tol, t_events=evs, pars=[1.0]) if eta > 0 else dict(tol=tol)
        if jacobian:
            vsys = hy.var_ode_sys(sys_, hy.var_args.vars, order=1)
            self.ta = hy.taylor_adaptive(vsys, [0.0, 0.0], **kw)
        else:
            self.ta = hy.taylor_adaptive(sys_, [0.0, 0.0], **kw)

    def accel(self, t, beta):
        return G * tau(2.0 * math.pi * self.f * t, beta)

    def run(self, x0, periods):
        """Integrates from (0, x0); returns (final state, Jacobian or None, steps)."""
        ta, f = self.ta, self.f
        T = 1.0 / f
        grid = np.arange(periods + 1) * T
        t1 = grid[-1]
        ta.time = 0.0
        st = ta.state
        st[:] = 0.0
        st[0], st[1] = x0
        if self.jac:
            st[2], st[5] = 1.0, 1.0
        steps = 0
        out = np.empty((periods + 1, 2))
        nxt = 0
        t = 0.0
        stuck = x0[1] == 0.0 and abs(self.accel(0.0, x0[0])) <= self.eta
        if eta_free := self.eta == 0.0:
            stuck = False
        if not stuck and not eta_free:
            ta.pars[0] = 1.0 if x0[1] > 0 or (x0[1] == 0 and self.accel(0, x0[0]) > 0) else -1.0
        else:
            self._stick(st)
        while True:
            if stuck:
                tr = next_release(f, t, st[0], self.eta)
                tr = t1 if tr is None or tr > t1 else tr
                while nxt <= periods and grid[nxt] <= tr:
                    out[nxt] = (st[0], 0.0)
                    nxt += 1
                if tr >= t1:
                    break
                t = tr
                ta.time = t
                ta.pars[0] = 1.0 if self.accel(t, st[0]) >= 0 else -1.0
                stuck = False
                continue
            # the grid starts at the current time (its first row is dropped)
            lead = 1 if grid[nxt] > ta.time else 0
            g = np.concatenate(([ta.time], grid[nxt:])) if lead else grid[nxt:]
            res = ta.propagate_grid(g, max_delta_t=T / 8)
            oc = res[0]
            steps += res[3]
            got = res[-1][lead:]
            if oc == hy.taylor_outcome.time_limit:
                n_done = len(got)
            else:
                n_done = int(np.count_nonzero(~np.isnan(got[:, 0])))
            out[nxt:nxt + n_done] = got[:n_done, :2]
            nxt += n_done
            if oc == hy.taylor_outcome.time_limit or nxt > periods:
                break
            # a terminal event: ω = 0 at ta.time; outcome −1 − i for event i
            s = ta.pars[0]
            if (int(oc) == -1) != (s > 0):
                continue
            t = ta.time
            st[1] = 0.0
            a = self.accel(t, st[0])
            if abs(a) <= self.eta:
                self._stick(st)
                stuck = True
            else:
                new = 1.0 if a > 0 else -1.0
                if self.jac and new != s:
                    ratio = (a - new * self.eta) / (a - s * self.eta)
                    st[4] *= ratio
                    st[5] *= ratio
                ta.pars[0] = new
        jac = np.array([[st[2], st[3]], [st[4], st[5]]]) if self.jac else None
        return out[-1].copy(), jac, steps

    def _stick(self, st):
        st[1] = 0.0
        if self.jac:
            st[4] = st[5] = 0.0


def best_time(fn, min_time):
    fn()
    best, spent = float("inf"), 0.0
    while spent < min_time:
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        best = min(best, dt)
        spent += dt
    return best


def gearbif_points(exe, name, w, tols, jacobian, min_time):
    args = [exe, "bench-integrators", "--theta-deg", "25", "--f", str(w["f"]),
            "--x0-deg", f"{math.degrees(w['x0'][0])},{w['x0'][1]}",
            "--periods", str(PERIODS), "--strobe", "--reference-tol", "1e-14",
            "--event-tols", "--fixed-steps", "--reg-tols",
            "--dop853-tols", ",".join(tols), "--taylor-tols", ",".join(tols),
            "--min-time", str(min_time), "--json"]
    if w["eta"] == 0.0:
        args += ["--eta", "0"]
    if not jacobian:
        args.append("--no-jacobian")
    rep = json.loads(subprocess.check_output(args))
    rep = rep.get("data", rep)
    return rep


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--gearbif", required=True)
    ap.add_argument("--tols", default="1e-6,1e-8,1e-10,1e-12")
    ap.add_argument("--min-time", type=float, default=1.0)
    ap.add_argument("--workloads", default=",".join(WORKLOADS))
    ap.add_argument("--out", default="docs/tables/peers")
    ap.add_argument("--commit", default="")
    a = ap.parse_args()
    tols = a.tols.split(",")
    rows = []
    notes = []
    for name in a.workloads.split(","):
        w = WORKLOADS[name]
        for jac in (False, True):
            rep = gearbif_points(a.gearbif, name, w, tols, jac, a.min_time)
            ref = rep["reference_x"]
            for p in rep["points"]:
                rows.append(dict(workload=name, jacobian=jac, method="gearbif " + p["family"].replace("event-driven ", ""),
                                 tol=p["tol"], error=p["error"], steps=p["steps"],
                                 us_per_period=p["time_s"] * 1e6 / PERIODS))
            check = HeyokaGear(w["f"], w["eta"], 1e-15, jac).run(w["x0"], PERIODS)[0]
            notes.append(f"{name}{' (Jacobian)' if jac else ''}: heyoka at tol 1e-15 differs from the "
                         f"reference by {max(abs(check[0]-ref[0]), abs(check[1]-ref[1])):.1e}")
            for tol in tols:
                hg = HeyokaGear(w["f"], w["eta"], float(tol), jac)
                x, _, steps = hg.run(w["x0"], PERIODS)
                err = max(abs(x[0] - ref[0]), abs(x[1] - ref[1]))
                dt = best_time(lambda: hg.run(w["x0"], PERIODS), a.min_time)
                rows.append(dict(workload=name, jacobian=jac, method="heyoka", tol=float(tol), error=err,
                                 steps=steps, us_per_period=dt * 1e6 / PERIODS))
            print(f"done {name} jacobian={jac}", file=sys.stderr, flush=True)
    write(a, rows, notes)


def write(a, rows, notes):
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    head = [
        "# gearbif against heyoka on the gear (generated by scripts/bench_peers.sh)",
        "",
        f"- machine: {os.cpu_count()} cores, {cpu}, {platform.system()} {platform.release()}; "
        f"Python {platform.python_version()}, heyoka {hy.__version__}",
        f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; gearbif commit {a.commit}; "
        f"load average at the end {os.getloadavg()[0]:.1f}",
        f"- workload: gear of the paper at Θ = 25°, {PERIODS} drive periods in one integration, "
        "a strobe sample at every period; best-of wall time per period; error = max(|Δβ|, |Δω|) "
        "at the end against gearbif's DOP853 at tol 1e-14",
        "",
    ] + [f"- {n}" for n in notes] + [""]
    lines = ["| workload | Jacobian | method | tol | error | steps | µs/period |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['workload']} | {'yes' if r['jacobian'] else 'no'} | {r['method']} | {r['tol']:.0e} | "
                     f"{r['error']:.1e} | {r['steps']} | {r['us_per_period']:.2f} |")
    with open(a.out + ".md", "w") as fh:
        fh.write("\n".join(head + lines) + "\n")
    with open(a.out + ".csv", "w") as fh:
        fh.write("workload,jacobian,method,tol,error,steps,us_per_period\n")
        for r in rows:
            fh.write(f"{r['workload']},{r['jacobian']},{r['method']},{r['tol']},{r['error']},{r['steps']},{r['us_per_period']}\n")
    print("\n".join(head + lines))


if __name__ == "__main__":
    main()
