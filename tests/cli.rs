//! The command-line interface, run as a process: outputs parse and agree with the library, and bad
//! input gives exit code 2 with a clear message and no output file.
#![cfg(feature = "cli")]

use gearbif::integrator::{EventDriven, FlowMethod, FlowOptions};
use gearbif::model::Gear;
use std::path::PathBuf;
use std::process::{Command, Output};

fn gearbif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gearbif"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gearbif-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is JSON")
}

fn rows(csv: &str) -> Vec<Vec<f64>> {
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect()
}

fn fails_with(args: &[&str], needle: &str) {
    let out = gearbif(args);
    assert_eq!(out.status.code(), Some(2), "args {args:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.to_lowercase().contains(&needle.to_lowercase()),
        "args {args:?}: stderr `{err}` lacks `{needle}`"
    );
}

#[test]
fn simulate_csv_matches_the_library_flow() {
    let out = gearbif(&[
        "simulate",
        "--theta-deg",
        "25",
        "--f",
        "2.7",
        "--x0-deg",
        "28.6478897565,2",
        "--periods",
        "3",
        "--samples-per-period",
        "20",
        "--tol",
        "1e-10",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.lines().next(), Some("t,alpha,beta,omega,delta"));
    let r = rows(&text);
    assert_eq!(r.len(), 61);
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let x0 = [28.6478897565f64.to_radians(), 2.0];
    let flow = EventDriven
        .flow(&gear, 0.0, x0, 3.0 / 2.7, &FlowOptions::with_tol(1e-10))
        .unwrap();
    let last = r.last().unwrap();
    assert!((last[0] - 3.0 / 2.7).abs() < 1e-12);
    assert!((last[2] - flow.x[0]).abs() < 1e-9 && (last[3] - flow.x[1]).abs() < 1e-8);
    for row in &r {
        assert!((row[1] - std::f64::consts::TAU * 2.7 * row[0]).abs() < 1e-9);
        assert!((row[4] - (row[2] - row[1])).abs() < 1e-12);
    }
}

#[test]
fn paper_convention_shifts_beta_by_pi() {
    let common = [
        "simulate",
        "--theta-deg",
        "25",
        "--f",
        "1.3",
        "--periods",
        "2",
    ];
    let phys = gearbif(&[&common[..], &["--x0-deg", "40,1"]].concat());
    let pap = gearbif(&[&common[..], &["--x0-deg", "220,1", "--convention", "paper"]].concat());
    let (a, b) = (
        rows(&String::from_utf8(phys.stdout).unwrap()),
        rows(&String::from_utf8(pap.stdout).unwrap()),
    );
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert!(
            (y[2] - x[2] - std::f64::consts::PI).abs() < 1e-7,
            "{x:?} {y:?}"
        );
        assert!((y[3] - x[3]).abs() < 1e-6);
    }
}

#[test]
fn simulate_json_summary_and_event_file() {
    let d = tmpdir("events");
    let (csv, ev) = (d.join("traj.csv"), d.join("events.csv"));
    let out = gearbif(&[
        "simulate",
        "--theta-deg",
        "31",
        "--f",
        "0.3",
        "--x0-deg",
        "57.29577951308232,0",
        "--periods",
        "3",
        "--json",
        "--out",
        csv.to_str().unwrap(),
        "--events",
        ev.to_str().unwrap(),
    ]);
    let v = json(&out);
    let n_ev = v["stats"]["events"].as_u64().unwrap() as usize;
    let text = std::fs::read_to_string(&ev).unwrap();
    assert_eq!(text.lines().next(), Some("t,beta,kind,to"));
    assert_eq!(text.lines().count() - 1, n_ev);
    let sticks = text.lines().filter(|l| l.contains(",stick,")).count();
    assert_eq!(sticks as u64, v["events"]["stick_starts"].as_u64().unwrap());
    assert!(sticks >= 2, "this orbit has stick phases");
    // at every stick event the output is at rest at the recorded β: the trajectory passes there
    let traj = rows(&std::fs::read_to_string(&csv).unwrap());
    assert_eq!(traj.len(), v["samples"].as_u64().unwrap() as usize);
    std::fs::remove_dir_all(d).ok();
}

#[test]
fn map_json_iterates_and_is_consistent() {
    let base = [
        "map",
        "--theta-deg",
        "25",
        "--f",
        "2.7",
        "--tol",
        "1e-11",
        "--json",
    ];
    let one = json(&gearbif(
        &[&base[..], &["--x0-deg", "28.6478897565,2"]].concat(),
    ));
    let img = [
        one["image"][0].as_f64().unwrap(),
        one["image"][1].as_f64().unwrap(),
    ];
    let x1 = format!("{},{}", img[0].to_degrees(), img[1]);
    let again = json(&gearbif(&[&base[..], &["--x0-deg", &x1]].concat()));
    let two = json(&gearbif(
        &[
            &base[..],
            &["--x0-deg", "28.6478897565,2", "--iterations", "2"],
        ]
        .concat(),
    ));
    for i in 0..2 {
        let (a, b) = (
            again["image"][i].as_f64().unwrap(),
            two["image"][i].as_f64().unwrap(),
        );
        assert!((a - b).abs() < 1e-7, "P(P(x)) = {a} vs P²(x) = {b}");
    }
    // the multipliers are the eigenvalues: product = det, sum = trace
    let mu = &one["multipliers"];
    let (r0, i0, r1, i1) = (
        mu[0]["re"].as_f64().unwrap(),
        mu[0]["im"].as_f64().unwrap(),
        mu[1]["re"].as_f64().unwrap(),
        mu[1]["im"].as_f64().unwrap(),
    );
    let det = one["det"].as_f64().unwrap();
    assert!((r0 * r1 - i0 * i1 - det).abs() < 1e-9 * (1.0 + det.abs()));
    assert!((r0 + r1 - one["trace"].as_f64().unwrap()).abs() < 1e-9);
    assert_eq!(one["param_names"].as_array().unwrap().len(), 5);
    // the half-period map twice is P_T up to the 2π shift
    let half = json(&gearbif(
        &[
            &base[..],
            &[
                "--x0-deg",
                "28.6478897565,2",
                "--section",
                "half",
                "--iterations",
                "2",
            ],
        ]
        .concat(),
    ));
    let d = one["image"][0].as_f64().unwrap() - half["image"][0].as_f64().unwrap();
    assert!((d - std::f64::consts::TAU).abs() < 1e-7, "{d}");
}

#[test]
fn bad_input_exits_2_with_a_message() {
    fails_with(&["simulate", "--f", "nan"], "`f` = NaN");
    fails_with(&["simulate", "--f", "-1"], "`f`");
    fails_with(&["simulate", "--zeta", "NaN"], "zeta");
    fails_with(&["simulate", "--theta-deg", "inf"], "theta");
    fails_with(&["simulate", "--tol", "0"], "tol");
    fails_with(&["simulate", "--x0-deg", "1,nan"], "x0");
    fails_with(&["simulate", "--x0-deg", "abc"], "x0");
    fails_with(
        &["simulate", "--samples-per-period", "0"],
        "samples-per-period",
    );
    fails_with(&["simulate", "--method", "euler"], "invalid value");
    fails_with(
        &["simulate", "--method", "regularised", "--epsilon", "0"],
        "epsilon",
    );
    fails_with(&["map", "--iterations", "0"], "iterations");
    fails_with(&["map", "--inertia=-1"], "inertia");
    let d = tmpdir("bad");
    let missing = d.join("missing.toml");
    fails_with(
        &["simulate", "--config", missing.to_str().unwrap()],
        "cannot read",
    );
    let broken = d.join("broken.toml");
    std::fs::write(&broken, "[gear]\nm1 = = 3\n").unwrap();
    fails_with(
        &["map", "--config", broken.to_str().unwrap()],
        "broken.toml",
    );
    let unknown = d.join("unknown.toml");
    std::fs::write(&unknown, "[gear]\nmass = 3\n").unwrap();
    fails_with(&["map", "--config", unknown.to_str().unwrap()], "mass");
    // no half-written output on failure
    let out = d.join("never.csv");
    fails_with(
        &["simulate", "--f", "nan", "--out", out.to_str().unwrap()],
        "NaN",
    );
    assert!(!out.exists());
    std::fs::remove_dir_all(d).ok();
}

#[test]
fn toml_config_sets_parameters() {
    let d = tmpdir("toml");
    let cfg = d.join("experiment.toml");
    std::fs::write(&cfg, "[gear]\ntheta_deg = 25.0\neta = 10.0\n").unwrap();
    let v = json(&gearbif(&[
        "map",
        "--config",
        cfg.to_str().unwrap(),
        "--f",
        "2.7",
        "--json",
    ]));
    assert!((v["eta"].as_f64().unwrap() - 10.0).abs() < 1e-15);
    let delta = 1.0 - 3.0 * 25f64.to_radians().sin().powi(2);
    assert!((v["delta"].as_f64().unwrap() - delta).abs() < 1e-12);
    std::fs::remove_dir_all(d).ok();
}

#[test]
fn bench_integrators_writes_csv_figure_and_json() {
    let d = tmpdir("bench");
    let (csv, svg) = (d.join("wp.csv"), d.join("wp.svg"));
    let v = json(&gearbif(&[
        "bench-integrators",
        "--event-tols",
        "1e-6,1e-9",
        "--dop853-tols",
        "1e-9",
        "--taylor-tols",
        "1e-9",
        "--fixed-steps",
        "50",
        "--reg-tols",
        "1e-6",
        "--reg-eps",
        "1e-3",
        "--min-time",
        "0",
        "--csv",
        csv.to_str().unwrap(),
        "--figure",
        svg.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(v["schema"], "gearbif.bench_integrators/1");
    let pts = v["points"].as_array().unwrap();
    let n_reg = usize::from(cfg!(feature = "diffsol-check"));
    // DP5 at two tolerances, DOP853 at one, Taylor at one, the fixed step, the regularised method
    assert_eq!(pts.len(), 5 + n_reg);
    let err = |i: usize| pts[i]["error"].as_f64().unwrap();
    assert!(err(1) < err(0) && err(1) < 1e-7);
    assert!(err(2) < 1e-7, "DOP853 at tol 1e-9: error {}", err(2));
    assert!(err(3) < 1e-7, "Taylor at tol 1e-9: error {}", err(3));
    // the paper's 50 steps per period: error far above the event-driven one, Jacobian wrong
    assert!(err(4) > 1e-3 && pts[4]["jac_error"].as_f64().unwrap() > 1e-2);
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), pts.len() + 1);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    fails_with(&["bench-integrators", "--event-tols", "0"], "tol");
    fails_with(
        &["bench-integrators", "--figure", "x.jpg", "--min-time", "0"],
        "svg",
    );
    std::fs::remove_dir_all(d).ok();
}

#[test]
fn synth_fit_diagnose_round_trip() {
    let dir = tmpdir("ident");
    let set = dir.join("set");
    let out = dir.join("out");
    let s = set.to_str().unwrap();
    let o = out.to_str().unwrap();
    // a small set: 3 ring-downs, 2 driven runs of 12 turns, a static torque
    let r = gearbif(&[
        "synth",
        "--effect",
        "static_torque",
        "--size",
        "6",
        "--out",
        s,
        "--ringdowns",
        "3",
        "--driven",
        "2",
        "--turns",
        "12",
        "--seed",
        "5",
        "--truth",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(set.join("experiment.toml").is_file() && set.join("truth.json").is_file());
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(set.join("truth.json")).unwrap()).unwrap();
    // fit: base parameters as JSON, g near the concealed truth (within 2%: a small set)
    let v = json(&gearbif(&["fit", s, "--json"]));
    assert_eq!(v["schema"], "gearbif.fit/1");
    let g = v["baseline"]["params"]["g"].as_f64().unwrap();
    let g_true = truth["g"].as_f64().unwrap();
    assert!((g - g_true).abs() < 0.02 * g_true, "g {g} vs {g_true}");
    // diagnose: report.json with the schema and report.md; the verdict names the concealed
    // effect, and its size, its phase and g agree with the truth within 3 of their reported σ
    // (measured on this set: amplitude 5.87 ± 0.11 s⁻² for 6, phase 59.3 ± 0.9° for 60°, g
    // 288.3 ± 0.37 for 287.5)
    let r = gearbif(&["diagnose", s, "--out", o, "--no-heldout", "--no-figures"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(rep["schema"], "gearbif.diagnosis/1");
    assert_eq!(rep["verdict"], "static_torque", "{rep}");
    assert!(out.join("report.md").is_file());
    let f = &rep["findings"][0]["params"];
    let num = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let (amp, amp_err) = (num(f, "amplitude"), num(f, "amplitude_err"));
    let size = truth["size"].as_f64().unwrap();
    let st = &truth["static_torque"];
    let phase_true = st[1]
        .as_f64()
        .unwrap()
        .atan2(st[0].as_f64().unwrap())
        .to_degrees();
    assert!(
        (amp - size).abs() <= 3.0 * amp_err,
        "amplitude {amp} ± {amp_err} vs {size}"
    );
    assert!(
        amp_err < 0.05 * size,
        "amplitude σ {amp_err} for a size of {size}"
    );
    let (ph, ph_err) = (num(f, "phase_deg"), num(f, "phase_err_deg"));
    assert!(
        (ph - phase_true).abs() <= 3.0 * ph_err,
        "phase {ph} ± {ph_err} vs {phase_true}"
    );
    let base = &rep["baseline"]["params"];
    let (gd, gd_err) = (num(base, "g"), num(base, "g_err"));
    assert!(
        (gd - g_true).abs() <= 3.0 * gd_err,
        "g {gd} ± {gd_err} vs {g_true}"
    );
    // model.json: the diagnosed gear, whose static torque is the finding's, runs in the dynamics
    // commands (`simulate --model`)
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("model.json")).unwrap()).unwrap();
    assert_eq!(model["schema"], "gearbif.model/1");
    assert_eq!(model["effects"][0], "static_torque", "{model}");
    let param = |name: &str| {
        model["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .and_then(|p| p["value"].as_f64())
            .unwrap_or_else(|| panic!("{name} missing from {model}"))
    };
    let a_file = param("static_a").hypot(param("static_b"));
    assert!(
        (a_file - amp).abs() < 1e-9 * amp,
        "model.json amplitude {a_file} vs report {amp}"
    );
    let m = out.join("model.json");
    let sim = json(&gearbif(&[
        "simulate",
        "--f",
        "1.5",
        "--periods",
        "2",
        "--json",
        "--model",
        m.to_str().unwrap(),
    ]));
    assert!(sim["x_end"][0].as_f64().unwrap().is_finite(), "{sim}");
    // --list names every catalogued effect the generator knows
    let l = gearbif(&["synth", "--list"]);
    let text = String::from_utf8_lossy(&l.stdout);
    for e in [
        "static_friction",
        "drive_steps",
        "parameter_drift",
        "input_compliance",
    ] {
        assert!(text.contains(e), "{e} missing from synth --list");
    }
    // bad input: exit 2, a message, no report
    fails_with(&["synth", "--effect", "nope", "--out", o], "unknown effect");
    let missing = dir.join("missing");
    let bad_out = dir.join("bad_out");
    fails_with(
        &[
            "diagnose",
            missing.to_str().unwrap(),
            "--out",
            bad_out.to_str().unwrap(),
        ],
        "experiment.toml",
    );
    assert!(!bad_out.join("report.json").exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn every_json_output_carries_its_schema_id() {
    // docs/formats.md lists these ids; each output is checked for its own
    let d = tmpdir("schema");
    let schema = |v: &serde_json::Value| v["schema"].as_str().unwrap_or("").to_string();
    assert_eq!(
        schema(&json(&gearbif(&["info", "--f", "5", "--json"]))),
        "gearbif.info/1"
    );
    assert_eq!(schema(&json(&gearbif(&["map", "--json"]))), "gearbif.map/1");
    let traj = d.join("traj.csv");
    let sim = json(&gearbif(&[
        "simulate",
        "--periods",
        "1",
        "--out",
        traj.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(schema(&sim), "gearbif.simulate/1");
    let cls = json(&gearbif(&[
        "classify",
        "--f",
        "5",
        "--settle",
        "5",
        "--record",
        "2",
        "--analysis",
        "4",
        "--json",
    ]));
    assert_eq!(schema(&cls), "gearbif.classify/1");
    let out = d.join("branch.json");
    let cont = json(&gearbif(&[
        "continue",
        "--f",
        "5",
        "--lock",
        "stable",
        "--range",
        "4:6",
        "--ds",
        "0.5",
        "--ds-max",
        "1",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(schema(&cont), "gearbif.branches/1");
    assert!(cont["branches"][0]["points"].as_array().unwrap().len() > 2);
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(file, cont);
    let loc = json(&gearbif(&[
        "locate",
        "--f",
        "39.8",
        "--kind",
        "fold",
        "--state-rad",
        "1.6,250",
        "--json",
    ]));
    assert_eq!(schema(&loc), "gearbif.locate/1");
    let bnd = json(&gearbif(&["boundary", "--step", "27.5", "--json"]));
    assert_eq!(schema(&bnd), "gearbif.curves/1");
    let sw = d.join("sweep");
    let r = gearbif(&[
        "sweep",
        "--rows",
        "theta:0:0:1",
        "--cols",
        "f:5:5:1",
        "--settle",
        "5",
        "--record",
        "2",
        "--analysis",
        "0",
        "--quiet",
        "--out",
        sw.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sw.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(schema(&v), "gearbif.sweep/1");
    // the old unit-less flags are gone: the unit is in the name
    fails_with(&["map", "--x0", "28,2"], "--x0-deg");
    fails_with(
        &["continue", "--f", "2", "--range", "1:3", "--state", "1,2"],
        "--state-rad",
    );
    std::fs::remove_dir_all(&d).ok();
}

/// Not on a terminal (a log file, a batch job), a sweep reports each finished row with the points
/// done and an estimate of the time left.
#[test]
fn sweep_logs_its_progress_and_time_left_when_not_on_a_terminal() {
    let dir = tmpdir("sweep-log");
    let out = dir.join("out");
    let o = gearbif(&[
        "sweep",
        "--rows",
        "theta:0:10:10",
        "--cols",
        "f:1:2:1",
        "--settle",
        "2",
        "--record",
        "1",
        "--analysis",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("sweep: 4 points"), "{err}");
    assert!(
        err.contains("4/4 points") && err.contains("s left"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
