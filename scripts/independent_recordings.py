"""Recording sets made without gearbif: an independent check of `gearbif diagnose`.

Pure Python (no numpy), its own integrator (classical RK4, step 2e-4 s, stick/slip switching by
the Filippov rule at velocity reversals), the gear of model.md at the stated set-up (Θ = Φ = 31°,
the paper's moments and distance), g, ζ, η drawn within a few percent, 12 ring-downs (100 frames/s,
3 s) and 8 driven runs (0.5–2.5 Hz, 80 turns, 50 samples per turn), camera noise 0.5° with 0.3 %
outlier frames of 5–15°. Effects, in forms the diagnosis catalog does not spell out:

  null_laplace    no effect; Laplace (not Gaussian) camera noise
  shaft_offset    true input shaft angle 37° where 31° is stated
  tilt_torque     7 sin(β − 0.7) + 2.5 cos(2β + 0.3) s⁻² on the output
  cubic_drag      −0.08 β̇³
  stribeck_exp    friction η + 0.6 η exp(−|β̇|/1.5)  (exponential, not Gaussian, decay)
  alpha_mod_fric  friction η (1 + 0.35 cos 2α)      (modulated by the input angle)
  sqrt_drag       −0.5 sgn(β̇) |β̇|^½               (sub-linear drag)
  torque_3h       3 sin(3β + 0.4) s⁻²               (only a third harmonic)
  torque_sqrt     5 sin(β + 1) s⁻² and the sub-linear drag above
  eta_drift       friction η (1 + 0.3 k/19) in run k of 20 (file order: a drift)
  freq_zeta       ζ (1 + 0.6 (f − 1.5 Hz)) in the driven runs; ring-downs ζ
  vib             2 sin(2π · 7.3 Hz · t) s⁻² (a vibration; 0.05° of motion, below the noise)
  latency9        β taken 9 ms before its time stamp
  asym_fric       friction η (1 + 0.2 d), d the direction of motion (direction-dependent friction)
  rel_zeta        damping ζ (1 + 0.5 cos 2(α − β))   (modulated by the relative angle)
  quad_coupling   0.06 g sin 2(α − β) s⁻² added to the dipole torque (a quadrupole term)
  g_saturating    g (1 − 0.08 (1 − e^(−k/4))) in run k (a drift that saturates)
  beta_offset     β recorded 4° above the true angle (camera zero offset)
  alpha_ripple    α(t) = 2πft + 0.15 sin 2πft, recorded as it is (a control: nothing to find)
  latency_cubic   β taken 5 ms early and the drag −0.05 β̇³ (two effects at once)
  static_fric     breakaway friction 1.5 η at rest, η in motion (a step, no decay width)
  stribeck_tilt   stribeck_exp and tilt_torque together (two effects at once)
  eta_warm        friction η (1 − 0.25 (1 − e^(−T/150 s))), T the session's running time
                  (the bearings warm up: a drift within the runs as well as across them)
  null_wander     camera noise 0.4° white plus a slow wander (AR(1), ρ = 0.99 per frame, 0.3°)
  null_jitter     frame times jittered by 1 ms (Gaussian) and recorded at the nominal time
  null_coarse     25 samples per turn, ring-downs at 50 frames/s
  beta_mod_fric   friction η (1 + 0.3 cos(β − 0.5))   (modulated by the output angle)
  shaft_latency   shaft_offset and latency 6 ms together
  cubic_alphafric cubic_drag and alpha_mod_fric together

Usage: python3 scripts/independent_recordings.py EFFECT SEED OUT_FOLDER
(writes experiment.toml, the CSVs and truth_blind.json with g, Δ, ζ, η).
"""
import math, random, sys, os, json
MU0=4e-7*math.pi
def base(theta_deg, phi_deg, m1=3.51,m2=3.51,r=0.04,I=6.45e-5):
    th,ph=math.radians(theta_deg),math.radians(phi_deg)
    c=MU0*m1*m2/(4*math.pi*r**3)
    return c/I, math.cos(th)*math.cos(ph)-2*math.sin(th)*math.sin(ph)
class Truth:
    def __init__(s, effect, rng):
        s.effect=effect
        s.g,s.delta=base(31,31)
        if effect in("shaft_offset","shaft_latency"): s.g,s.delta=base(37,31)
        s.g*=rng.uniform(0.97,1.03)
        s.zeta=1.1*rng.uniform(0.9,1.1); s.eta=23.1*rng.uniform(0.9,1.1)
        s.run=0; s.fhz=1.5; s.t=0.0; s.t0=0.0
    def smooth(s,a,b,v):
        g=s.g*(1-0.08*(1-math.exp(-s.run/4))) if s.effect=="g_saturating" else s.g
        f=g*(-math.sin(a)*math.cos(b)+s.delta*math.cos(a)*math.sin(b))-s.zeta*v
        e=s.effect
        if e in("tilt_torque","stribeck_tilt"): f+=7.0*math.sin(b-0.7)+2.5*math.cos(2*b+0.3)
        if e in("cubic_drag","cubic_alphafric"): f-=0.08*v**3
        if e=="latency_cubic": f-=0.05*v**3
        if e=="rel_zeta": f-=s.zeta*0.5*math.cos(2*(a-b))*v
        if e=="quad_coupling": f+=0.06*s.g*math.sin(2*(a-b))
        if e in("sqrt_drag","torque_sqrt"): f-=0.5*math.copysign(math.sqrt(abs(v)),v)
        if e=="torque_3h": f+=3.0*math.sin(3*b+0.4)
        if e=="torque_sqrt": f+=5.0*math.sin(b+1.0)
        if e=="vib": f+=2.0*math.sin(2*math.pi*7.3*s.t)
        if e=="freq_zeta": f-=s.zeta*0.6*(s.fhz-1.5)*v
        return f
    def fric(s,a,b,v,d):
        """Friction level R ≥ 0 for motion in direction d = ±1."""
        e=s.effect; R=s.eta
        if e in("stribeck_exp","stribeck_tilt"): R+=0.6*s.eta*math.exp(-abs(v)/1.5)
        if e in("alpha_mod_fric","cubic_alphafric"): R*=1+0.35*math.cos(2*a)
        if e=="beta_mod_fric": R*=1+0.3*math.cos(b-0.5)
        if e=="eta_drift": R*=1+0.3*s.run/19
        if e=="asym_fric": R*=1+0.2*d
        if e=="eta_warm": R*=1-0.25*(1-math.exp(-(s.t0+s.t)/150.0))
        return R
    def breakaway(s,a,b,d):
        """Friction level that holds the output at rest."""
        R=s.fric(a,b,0.0,d)
        return 1.5*R if s.effect=="static_fric" else R
def simulate(tr, alpha_fn, b0, v0, tend, dt, tsamp):
    out=[]; t=0.0; b=b0; v=v0; stuck=False; k=0
    def acc(t,b,v,sg):
        a=alpha_fn(t); tr.t=t
        return tr.smooth(a,b,v)-sg*tr.fric(a,b,v,sg)
    while k<len(tsamp):
        # emit samples inside [t, t+dt)
        while k<len(tsamp) and tsamp[k]<t+dt*0.5:
            out.append(b); k+=1
        a=alpha_fn(t)
        if tr.effect=="eta_warm": tr.t=t  # the friction's clock also runs while stuck
        if stuck:
            fs=tr.smooth(a,b,0.0)
            if abs(fs)>tr.breakaway(a,b,math.copysign(1,fs)): stuck=False; sg=math.copysign(1,fs)
            else: t+=dt; continue
        else: sg=math.copysign(1,v) if v!=0 else math.copysign(1,tr.smooth(a,b,0.0))
        k1b=v; k1v=acc(t,b,v,sg)
        k2b=v+0.5*dt*k1v; k2v=acc(t+0.5*dt,b+0.5*dt*k1b,v+0.5*dt*k1v,sg)
        k3b=v+0.5*dt*k2v; k3v=acc(t+0.5*dt,b+0.5*dt*k2b,v+0.5*dt*k2v,sg)
        k4b=v+dt*k3v; k4v=acc(t+dt,b+dt*k3b,v+dt*k3v,sg)
        nb=b+dt/6*(k1b+2*k2b+2*k3b+k4b); nv=v+dt/6*(k1v+2*k2v+2*k3v+k4v)
        if nv*sg<0:  # velocity reversal within the step: linear interpolation to v=0
            frac=v/(v-nv); nb=b+frac*(nb-b); 
            a2=alpha_fn(t+frac*dt)
            fs=tr.smooth(a2,nb,0.0)
            if abs(fs)<=tr.breakaway(a2,nb,math.copysign(1,fs)): stuck=True; nv=0.0
            else: nv=0.0 if frac<1 else nv
        b,v=nb,nv; t+=dt
    return out
class Wander:
    """A slowly wandering camera zero: AR(1) with ρ = 0.99 per frame, stationary σ 0.3°."""
    def __init__(s,rng): s.rng=rng; s.w=rng.gauss(0,math.radians(0.3))
    def __call__(s):
        s.w=0.99*s.w+math.sqrt(1-0.99**2)*s.rng.gauss(0,math.radians(0.3)); return s.w
def noise(rng,kind,sig,wander=None):
    if wander is not None: return wander()+noise(rng,"gauss",math.radians(0.4))
    if kind=="laplace":
        u=rng.random()-0.5; x=-sig/math.sqrt(2)*math.copysign(1,u)*math.log(1-2*abs(u))
    else: x=rng.gauss(0,sig)
    if rng.random()<0.003: x+=math.radians(rng.choice([-1,1])*rng.uniform(5,15))
    return x
def main(effect, seed, out):
    rng=random.Random(seed); tr=Truth(effect,rng); os.makedirs(out,exist_ok=True)
    sig=math.radians(0.5); nk="laplace" if effect=="null_laplace" else "gauss"
    off=math.radians(4.0) if effect=="beta_offset" else 0.0  # camera zero offset
    fps,spt=(50,25) if effect=="null_coarse" else (100,50)  # frames/s, samples per turn
    clock=0.0  # the session's running time (eta_warm)
    def sample_times(ts,lat):
        """When the frames stamped ts were taken: lat earlier, or jittered (null_jitter)."""
        if effect!="null_jitter": return [max(0.0,x-lat) for x in ts]
        out=[]
        for x in ts: out.append(max(out[-1] if out else 0.0, x+rng.gauss(0,1e-3)))
        return out
    runs=[]
    for i in range(12):
        a0=math.radians(15+30*i+rng.uniform(-5,5))
        # release from rest 60-100 deg away from equilibrium
        b0=rng.uniform(-math.pi,math.pi)
        ts=[j/fps for j in range(int(3*fps))]
        tr.run=i; tr.fhz=1.5; tr.t0=clock
        lat={"latency9":0.009,"latency_cubic":0.005,"shaft_latency":0.006}.get(tr.effect,0.0)
        bs=simulate(tr,lambda t:a0,b0,0.0,3.0,2e-4,sample_times(ts,lat))
        clock+=3.0
        fn=f"rd_{i:02d}.csv"
        wd=Wander(rng) if effect=="null_wander" else None
        with open(os.path.join(out,fn),"w") as f:
            f.write("t,alpha,beta\n")
            for t,b in zip(ts,bs): f.write(f"{t:.6f},{a0:.6f},{b+off+noise(rng,nk,sig,wd):.6f}\n")
        runs.append(("ringdown",math.degrees(a0),fn))
    for i in range(8):
        fhz=0.5+2.0*i/7
        n=80*spt; ts=[j/(spt*fhz) for j in range(n)]
        rip=0.15 if tr.effect=="alpha_ripple" else 0.0  # the motor's speed ripple
        al=lambda t,fhz=fhz,rip=rip: 2*math.pi*fhz*t+rip*math.sin(2*math.pi*fhz*t)
        tr.run=12+i; tr.fhz=fhz; tr.t0=clock
        lat={"latency9":0.009,"latency_cubic":0.005,"shaft_latency":0.006}.get(tr.effect,0.0)
        b0=rng.uniform(-math.pi,math.pi)
        bs=simulate(tr,al,b0,0.0,ts[-1]+0.01,min(2e-4,0.02/fhz/50*5),sample_times(ts,lat))
        clock+=ts[-1]
        fn=f"dr_{i:02d}.csv"
        wd=Wander(rng) if effect=="null_wander" else None
        with open(os.path.join(out,fn),"w") as f:
            f.write("t,alpha,beta\n")
            for t,b in zip(ts,bs): f.write(f"{t:.6f},{math.remainder(al(t),2*math.pi):.6f},{math.remainder(b+off+noise(rng,nk,sig,wd),2*math.pi):.6f}\n")
        runs.append(("driven",fhz,fn))
    with open(os.path.join(out,"experiment.toml"),"w") as f:
        f.write("[gear]\nm1 = 3.51\nm2 = 3.51\nr = 0.04\ntheta_deg = 31.0\nphi_deg = 31.0\nzeta = 1.1\neta = 23.1\nshaft_mass = 0.32\nbearing_bore = 0.03\n")
        for k,x,fn in runs:
            f.write(f'\n[[run]]\nkind = "{k}"\n'+(f"alpha0_deg = {x}\n" if k=="ringdown" else f"f_hz = {x}\n")+f'file = "{fn}"\n')
    json.dump({"effect":effect,"g":tr.g,"delta":tr.delta,"zeta":tr.zeta,"eta":tr.eta},open(os.path.join(out,"truth_blind.json"),"w"))
main(sys.argv[1], int(sys.argv[2]), sys.argv[3])
