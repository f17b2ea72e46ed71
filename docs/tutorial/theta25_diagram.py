"""The bifurcation diagram of the magnetic gear at Θ = 25° from Python (docs/tutorial.md).

Continues the symmetric orbit (fixed point of the half-period map G, one turn per period) in the
drive frequency f, locates its special points, switches at the symmetry-breaking points onto the
asymmetric (T-periodic) branches and at the flip onto the period-doubled branch — as the Rust
example examples/fig9_continuation.rs does — prints every located special point and plots the
branches with matplotlib.

    python docs/tutorial/theta25_diagram.py [--out theta25_diagram.png] [--quick]

--quick (or the environment variable GEARBIF_TUTORIAL_QUICK=1) continues over 2.2–2.7 Hz only and
skips the period doubling: the tests run it that way.
"""

import argparse
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gearbif  # noqa: E402

# special points: black symbols of distinct shapes (the branches use the colour cycle)
MARKERS = {
    "fold": ("s", "black"),
    "flip": ("D", "black"),
    "symmetry_breaking": ("o", "black"),
    "neimark_sacker": ("^", "black"),
    "nonsmooth": ("x", "black"),
}


def compute(quick: bool):
    """The branches: [(name, Branch)], continuing in f from the README's start orbit."""
    lo, hi = (2.2, 2.7) if quick else (1.5, 3.0)
    start = [2.98, 0.6]  # (β [rad], ω [rad/s]) near the symmetric orbit
    gear = gearbif.Gear.paper(25.0, lo)
    sym = gearbif.continuation(gear, start, range=(lo, hi), ds=0.02, ds_max=0.05)
    branches = [("symmetric (G, 1 turn per period)", sym)]
    sb = [s for s in sym.specials if s.kind == "symmetry_breaking"]
    for s in sb[::-1] if not quick else sb[-1:]:
        asym, _ = gearbif.switch_branch(sym, s, dparam=-1e-3, ds=-0.005, ds_max=0.02, max_steps=400)
        branches.append((f"asymmetric (P_T), from SB at {s.param:.3f} Hz", asym))
    if not quick:
        last = branches[1][1]
        for level in (1, 2):
            flips = [s for s in last.specials if s.kind == "flip"]
            if not flips:
                break
            try:
                pd, _ = gearbif.switch_branch(last, flips[0], dparam=-1e-4, ds=-0.002, ds_max=0.01,
                                              max_steps=300, range=(1.7, hi))
            except gearbif.ContinuationError as e:
                print(f"switching at the flip at {flips[0].param:.6f} Hz failed: {e}")
                break
            branches.append((f"period-{2 * last.spec['iterations']} (P_T^{2 * last.spec['iterations']})", pd))
            last = pd
    return branches


def report(branches):
    for name, b in branches:
        print(f"{name}: {len(b)} points, stop {b.stop['reason']}")
        for s in b.specials:
            mu = ", ".join(f"{z.real:+.6f}{z.imag:+.6f}i" for z in s.multipliers)
            print(f"  {s.label:<18} f = {s.param:.9f} ± {s.precision:.1e} Hz   μ = ({mu})")


def plot(branches, out: str):
    fig, ax = plt.subplots(figsize=(9, 5), layout="constrained")
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    seen = set()
    for i, (name, b) in enumerate(branches):
        f, beta = b.param, np.degrees(np.mod(b.beta, 2 * math.pi))
        # break the line where β wraps around 360°
        jumps = np.where(np.abs(np.diff(beta)) > 180)[0] + 1
        c = colors[i % len(colors)]
        for k, (fs, bs, st) in enumerate(zip(np.split(f, jumps), np.split(beta, jumps), np.split(b.stable, jumps))):
            # the whole branch thin and dashed (unstable), the stable parts over it, solid
            ax.plot(fs, bs, "--", color=c, lw=1.0, label=f"{name}, unstable" if k == 0 else None)
            ax.plot(fs, np.where(st, bs, np.nan), "-", color=c, lw=2.0, label=f"{name}, stable" if k == 0 else None)
        for s in b.specials:
            m, mc = MARKERS[s.kind]
            label = s.label if s.kind not in seen else None
            seen.add(s.kind)
            ax.plot(s.param, math.degrees(s.x[0] % (2 * math.pi)), m, color=mc, ms=7, mfc="none", mew=1.5,
                    label=label, zorder=5)
    ax.set_xlabel("drive frequency f [Hz]")
    ax.set_ylabel("output angle β at t = 0 (mod 360°) [deg]")
    ax.set_title("Θ = 25°: periodic orbits and their special points")
    ax.grid(alpha=0.3)
    fig.legend(loc="outside right upper", fontsize=8)
    fig.savefig(out, dpi=130)
    print(f"wrote {out}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="theta25_diagram.png", help="figure file (.png, .svg, .pdf)")
    ap.add_argument("--quick", action="store_true", help="2.2–2.7 Hz, no period doubling (tests)")
    a = ap.parse_args()
    quick = a.quick or os.environ.get("GEARBIF_TUTORIAL_QUICK") == "1"
    branches = compute(quick)
    report(branches)
    plot(branches, a.out)


if __name__ == "__main__":
    main()
