//! Bad input for every command of the binary: exit code 2, a message naming the problem, and no
//! file left behind. Each case runs in an empty working folder (so default output folders such as
//! `sweep-out` or `figures` would show up there) and must fail before any heavy work.
#![cfg(feature = "cli")]

use std::path::{Path, PathBuf};
use std::process::Command;

/// Fixtures shared by the cases: an existing file, an existing folder, config files and recording
/// sets with one defect each. Referenced in the table as `{name}`.
struct Fixtures {
    root: PathBuf,
}

impl Fixtures {
    fn new() -> Self {
        let root = std::env::temp_dir().join(format!("gearbif-badin-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(root.join("dir")).unwrap();
        let w = |p: &str, s: &str| {
            let p = root.join(p);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, s).unwrap();
        };
        w("file", "an ordinary file\n");
        w("angle.toml", "[gear]\ntheta_deg = 1e308\n");
        w("syntax.toml", "[gear]\nm1 = = 3\n");
        w("unknown.toml", "[gear]\nmass = 3\n");
        w("nan.toml", "[gear]\neta = nan\n");
        w("zeta.toml", "[gear]\nm1 = 3.51\n\nzeta = 1e300\n");
        let gear = "[gear]\nm1 = 3.51\nm2 = 3.51\nr = 0.04\ntheta_deg = 31.0\nphi_deg = 31.0\n";
        let run = "\n[[run]]\nkind = \"driven\"\nf_hz = 1.0\nfile = \"a.csv\"\n";
        w("set-nan/experiment.toml", &format!("{gear}{run}"));
        w("set-nan/a.csv", "t,alpha,beta\n0,0,0\n0.1,0,NaN\n");
        w("set-back/experiment.toml", &format!("{gear}{run}"));
        w("set-back/a.csv", "t,alpha,beta\n0,0,0\n0.2,0,0\n0.1,0,0\n");
        w(
            "set-kind/experiment.toml",
            &format!("{gear}{}", run.replace("driven", "spin")),
        );
        w(
            "set-abs/experiment.toml",
            &format!("{gear}{}", run.replace("a.csv", "/dev/zero")),
        );
        w(
            "set-angle/experiment.toml",
            &format!("{}{run}", gear.replace("31.0\nphi", "1e308\nphi")),
        );
        w("set-nofile/experiment.toml", &format!("{gear}{run}"));
        w("set-empty/experiment.toml", &format!("{gear}{run}"));
        w("set-empty/a.csv", "");
        // a run file reached through a symbolic link to a folder outside the set
        w(
            "set-link/experiment.toml",
            &format!("{gear}{}", run.replace("a.csv", "d/file")),
        );
        #[cfg(unix)]
        std::os::unix::fs::symlink(&root, root.join("set-link/d")).unwrap();
        // a Latin-1 byte on line 3
        w("set-latin1/experiment.toml", &format!("{gear}{run}"));
        std::fs::write(
            root.join("set-latin1/a.csv"),
            b"t,alpha,beta\n0,0,0\n# caf\xe9\n0.1,0,0\n",
        )
        .unwrap();
        // a drive frequency no double period can hold, on line 10
        w(
            "set-fhz/experiment.toml",
            &format!("{gear}{}", run.replace("1.0", "1e300")),
        );
        w("set-fhz/a.csv", "t,alpha,beta\n0,0,0\n0.1,0,0\n");
        // 0.5 Hz data declared as 50 Hz, and 0.5 Hz data with angles in degrees
        let ramp = |scale: f64| {
            let mut c = String::from("t,alpha,beta\n");
            for k in 0..100 {
                let t = 0.04 * k as f64;
                c += &format!("{t},{},0.1\n", scale * std::f64::consts::PI * t);
            }
            c
        };
        w(
            "set-f50/experiment.toml",
            &format!("{gear}{}", run.replace("1.0", "50.0")),
        );
        w("set-f50/a.csv", &ramp(1.0));
        w(
            "set-deg/experiment.toml",
            &format!("{gear}{}", run.replace("1.0", "0.5")),
        );
        w("set-deg/a.csv", &ramp(180.0 / std::f64::consts::PI));
        // a valid set, and output folders holding what a result would not
        w(
            "set-ok/experiment.toml",
            &format!("{gear}\n[[run]]\nkind = \"ringdown\"\nalpha0_deg = 30.0\nfile = \"a.csv\"\n"),
        );
        let mut ring = String::from("t,alpha,beta\n");
        for k in 0..50 {
            ring += &format!(
                "{},0.5235987755982988,{}\n",
                0.01 * k as f64,
                0.1 * (k as f64 * 0.3).cos()
            );
        }
        w("set-ok/a.csv", &ring);
        w("out-json/report.json/inside", "");
        w("out-foreign/data.csv", "mine\n");
        // r = -1 on line 4 of experiment.toml
        w(
            "set-r/experiment.toml",
            &format!("{}{run}", gear.replace("r = 0.04", "r = -1")),
        );
        Self { root }
    }

    fn expand(&self, arg: &str) -> String {
        let mut s = arg.to_string();
        while let (Some(a), Some(b)) = (s.find('{'), s.find('}')) {
            if b < a {
                break;
            }
            let name = s[a + 1..b].to_string();
            s.replace_range(a..=b, self.root.join(name).to_str().unwrap());
        }
        s
    }

    /// Every file under the fixtures, to check that no case writes into them.
    fn listing(&self) -> Vec<PathBuf> {
        listing(&self.root)
    }
}

fn listing(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            out.push(e.path());
            // not through symbolic links (a fixture links back to the root)
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                out.extend(listing(&e.path()));
            }
        }
    }
    out.sort();
    out
}

/// (arguments, text the message must contain).
const CASES: &[(&str, &str)] = &[
    // no command, unknown command, unknown flag (clap's own errors)
    ("", "Usage"),
    ("frobnicate", "unrecognized subcommand"),
    ("info --bogus", "unexpected argument"),
    // info
    ("info --theta-deg 1e308", "theta_deg"),
    ("info --phi-deg -361", "phi_deg"),
    ("info --f 0", "`f`"),
    ("info --f nan", "`f` = NaN"),
    ("info --m1 -1", "m1"),
    ("info --m2 0", "m2"),
    ("info --inertia inf", "inertia"),
    ("info --r 1e-300", "`g`"),
    ("info --zeta -0.1", "zeta"),
    ("info --eta nan", "eta"),
    ("info --convention sideways", "invalid value"),
    ("info --config {missing.toml}", "cannot read"),
    ("info --config {angle.toml}", "angle.toml:2"),
    ("info --config {syntax.toml}", "syntax.toml:2"),
    ("info --config {unknown.toml}", "mass"),
    ("info --config {nan.toml}", "nan.toml:2"),
    ("info --config {zeta.toml}", "zeta.toml:4"),
    ("info --config {dir}", "cannot read"),
    // simulate
    ("simulate --theta-deg 1e308", "theta_deg"),
    ("simulate --f -1", "`f`"),
    ("simulate --f 1e5", "[1e-3, 1e4]"),
    ("simulate --tol 1", "tol"),
    ("simulate --tol 0", "tol"),
    ("simulate --tol 1e-300", "`tol` = 1e-300"),
    ("simulate --inertia 1e-300", "`g`"),
    ("simulate --zeta 1e300", "`zeta` = 1e300"),
    ("classify --f 1.3 --zeta 1e12", "`zeta` = 1e12"),
    ("simulate --eta 1e300", "`eta` = 1e300"),
    ("sweep --quiet --cols zeta:0:1e6:1e5", "`zeta`"),
    ("simulate --periods 1e12", "periods"),
    ("simulate --periods 0", "periods"),
    ("simulate --samples-per-period 0", "samples-per-period"),
    ("simulate --x0-deg 1e308,0", "x0"),
    ("simulate --x0-deg 0,1e7", "omega"),
    ("simulate --x0-deg abc", "x0"),
    ("simulate --method euler", "invalid value"),
    ("simulate --method fixed --steps 0", "steps"),
    ("simulate --method regularised --epsilon 2", "epsilon"),
    ("simulate --out {file}/x.csv", "not a folder"),
    ("simulate --out {dir}", "is a folder"),
    ("simulate --events {file}/e.csv --out t.csv", "not a folder"),
    // map
    ("map --iterations 0", "iterations"),
    ("map --iterations 2000000", "iterations"),
    ("map --inertia=-1", "inertia"),
    ("map --section diagonal", "invalid value"),
    ("map --f inf", "`f`"),
    // continue
    ("continue --f 1.3", "--range"),
    ("continue --f 1.3 --range 2:1", "lo < hi"),
    ("continue --f 1.3 --range 0:nan", "lo < hi"),
    ("continue --f 1.3 --range 0:x", "not a number"),
    ("continue --f 1.3 --range 0:inf", "lo < hi"),
    ("continue --f 0 --range 0:2", "`f`"),
    ("continue --f 1.3 --range -1:2 --direction down", "`f` = -1"),
    ("continue --f 1.3 --range 0:2", "`f` = 0"),
    (
        "continue --f 1.3 --range 1e-5:2 --max-steps 30",
        "`f` = 1e-5",
    ),
    ("continue --f 1.3 --range 1:2e4", "[1e-3, 1e4]"),
    ("continue --f 1.3 --range 0:400 --param theta", "theta_deg"),
    ("continue --f 1.3 --range -1:2 --param zeta", "zeta"),
    ("diagram --range -5:3 --param eta", "eta"),
    ("continue --f 1.3 --range 0.5:2 --ds 0", "--ds"),
    ("continue --f 1.3 --range 0.5:2 --ds 1 --ds-max 0.1", "--ds"),
    ("continue --f 1.3 --range 0.5:2 --ds-max=-1", "ds-max"),
    ("continue --f 1.3 --range 0.5:2 --max-steps 0", "max-steps"),
    ("continue --f 1.3 --range 0.5:2 --tol 0", "tol"),
    (
        "continue --f 1.3 --range 0.5:2 --max-multiplier 0.5",
        "max-multiplier",
    ),
    (
        "continue --f 1.3 --range 0.5:2 --lock sideways",
        "stable or unstable",
    ),
    (
        "continue --f 1.3 --range 0.5:2 --state-rad 1e9,0 --winding 1",
        "beta",
    ),
    ("continue --f 1.3 --range 0.5:2 --winding 5000", "winding"),
    ("continue --f 1.3 --range 0.5:2 --period 0", "period"),
    (
        "continue --f 1.3 --range 0.5:2 --direction left",
        "up or down",
    ),
    ("continue --f 1.3 --range 0.5:2 --param mass", "mass"),
    (
        "continue --f 1.3 --range 0.5:2 --section twisted",
        "sym or strob",
    ),
    (
        "continue --f 1.3 --range 0.5:2 --plot branch.jpg",
        ".svg or .png",
    ),
    ("continue --f 1.3 --range 0.5:2 --out {dir}", "is a folder"),
    (
        "continue --f 1.3 --range 0.5:2 --theta-deg 400",
        "theta_deg",
    ),
    // diagram
    ("diagram", "--range"),
    ("diagram --range 3:1", "lo < hi"),
    ("diagram --range 1.5:3 --grid 0", "grid"),
    ("diagram --range 1.5:3 --max-period 0", "max-period"),
    ("diagram --range 1.5:3 --tol 0", "tol"),
    ("diagram --range 1.5:3 --ds 1 --ds-max 0.1", "--ds"),
    ("diagram --range 1.5:3 --param mass", "mass"),
    ("diagram --range 1.5:3 --plot d.jpg", ".svg or .png"),
    ("diagram --range 1.5:3 --out {dir}", "is a folder"),
    ("diagram --range 0:3", "`f`"),
    // locate
    ("locate --f 1.3 --kind cusp --state-rad 0,0", "kind"),
    ("locate --f 1.3 --kind fold --state-rad nan,0", "state"),
    ("locate --f 1.3 --kind fold --state-rad 0,0 --tol 2", "tol"),
    (
        "locate --f 1.3 --kind fold --state-rad 0,0 --period 0",
        "period",
    ),
    (
        "locate --f 1.3 --kind fold --state-rad 0,0 --winding 99999",
        "winding",
    ),
    (
        "locate --f 1.3 --kind fold --state-rad 0,0 --param mass",
        "mass",
    ),
    (
        "locate --f 1.3 --kind fold --state-rad 0,0 --section x",
        "sym or strob",
    ),
    ("locate --f=-2 --kind fold --state-rad 0,0", "`f`"),
    ("locate --f 1.3 --kind fold", "--state-rad"),
    // boundary
    ("boundary --step 0", "--step"),
    ("boundary --step 1e-9", "--step"),
    ("boundary --step nan", "--step"),
    ("boundary --range 5:1", "lo < hi"),
    ("boundary --tol 0", "tol"),
    ("boundary --kind cusp", "kind"),
    ("boundary --free mass", "mass"),
    ("boundary --winding 5000", "winding"),
    ("boundary --start-state-rad 0,0", "--start-free"),
    ("boundary --start-state-rad 0,1e9 --start-free 1", "omega"),
    ("boundary --plot b.gif", ".svg or .png"),
    ("boundary --out {file}/b.json", "not a folder"),
    // a start guess far from the fold: the corrector's excursion is named as a bad start
    (
        "boundary --free f --along eta --start-free 39.8 --start-state-rad 1.5808,250.3",
        "start nearer",
    ),
    // classify
    ("classify --f 1.3 --settle 2000000", "settle"),
    ("classify --f 1.3 --record 0", "record"),
    ("classify --f 1.3 --analysis 1", "analysis"),
    ("classify --f 1.3 --alpha0-deg 1e308", "alpha0_deg"),
    ("classify --f 1.3 --beta0-deg inf", "beta0_deg"),
    ("classify --f 1.3 --tol 0", "tol"),
    ("classify --f nan", "`f`"),
    ("classify --f 1.3 --eta -1", "eta"),
    // basins
    ("basins --quiet --f nan", "`f`"),
    ("basins --quiet --f 2 --tol 0", "tol"),
    ("basins --quiet --f 2 --cells-beta 0", "cells-beta"),
    ("basins --quiet --f 2 --max-steps 3", "max-steps"),
    ("basins --quiet --f 2 --omega-range 5:1", "range"),
    ("basins --quiet --f 2 --kick-norm energy", "kick norm"),
    ("basins --quiet --f 2 --kick-max -1", "max_kick"),
    ("basins --quiet --f 2 --out {file}/b", "not a folder"),
    ("basins --quiet --f 2 --f-values 1:2:0", "f-values"),
    // sweep
    ("sweep --quiet --rows theta:0:1e308:1e307", "theta_deg"),
    ("sweep --quiet --cols f:0:3:1", "`f`"),
    ("sweep --quiet --cols f:1:1e5:1e4", "`f`"),
    ("sweep --quiet --rows theta:0:50:-10", "step"),
    ("sweep --quiet --rows theta:0:50:0", "step"),
    ("sweep --quiet --cols f:1:2:1e13:log", "at most 1e7"),
    ("sweep --quiet --cols f:1:2:1e20:log", "at most 1e7"),
    ("sweep --quiet --cols f:1:2:1e9:log", "at most 1e7"),
    (
        "sweep --quiet --rows theta:0:10:0.001 --cols f:1:2:0.0001",
        "at most 1e7",
    ),
    ("sweep --quiet --rows mass:0:1:1", "mass"),
    (
        "sweep --quiet --rows theta:0:10:5 --cols theta:0:10:5",
        "different parameters",
    ),
    ("sweep --quiet --rows theta:0:1:x", "not a number"),
    ("sweep --quiet --cols zeta:-1:1:1", "zeta"),
    ("sweep --quiet --cols inertia:0:1e-4:5e-5", "inertia"),
    ("sweep --quiet --tol 1", "tol"),
    ("sweep --quiet --settle-tol 0", "settle_tol"),
    ("sweep --quiet --settle-nonperiodic 0", "settle_nonperiodic"),
    ("sweep --quiet --record 0", "record"),
    ("sweep --quiet --analysis 1", "analysis"),
    ("sweep --quiet --settle 9999999", "settle"),
    ("sweep --quiet --alpha0-deg 1e308", "alpha0_deg"),
    ("sweep --quiet --f 0", "`f`"),
    ("sweep --quiet --out {file}", "not a folder"),
    ("sweep --quiet --theta-deg nan", "theta_deg"),
    ("sweep --quiet --shard x", "--shard"),
    ("sweep --quiet --shard 2/2", "shard"),
    ("sweep --quiet --shard 0/0", "shard"),
    ("sweep --quiet --shard 7/8", "empty"),
    ("sweep merge", "dirs"),
    ("sweep merge {dir}", "not a shard checkpoint"),
    ("sweep merge {missing}", "not a shard checkpoint"),
    // figure
    ("figure fig5 --quiet --theta-deg 1e308", "theta_deg"),
    ("figure fig5 --quiet --out {file}", "not a folder"),
    ("figure fig99", "invalid value"),
    ("figure fig7 --quiet --config {angle.toml}", "angle.toml:2"),
    // report
    ("report --quiet --eta -1", "eta"),
    ("report --quiet --r 0", "`r`"),
    ("report --quiet --out {file}", "not a folder"),
    ("report --quiet --out {out-foreign}", "file `data.csv`"),
    // synth
    ("synth --effect nope --out o", "unknown effect"),
    ("synth --effect none", "--out"),
    ("synth --effect none --out o --f-min 3 --f-max 1", "--f-min"),
    ("synth --effect none --out o --f-min 0", "f_min"),
    (
        "synth --effect none --out o --ringdowns 0 --driven 0",
        "nothing to record",
    ),
    ("synth --effect none --out o --ringdowns 5000", "ringdowns"),
    ("synth --effect none --out o --outliers 1", "outliers"),
    ("synth --effect none --out o --gaps=-0.5", "gaps"),
    ("synth --effect none --out o --turns 0", "turns"),
    ("synth --effect none --out o --noise-deg=-1", "noise_deg"),
    ("synth --effect none --out o --fps 0", "fps"),
    (
        "synth --effect none --out o --samples-per-turn 2",
        "samples-per-turn",
    ),
    ("synth --effect none --out o --latency nan", "latency"),
    (
        "synth --effect none --out o --turns 0.01 --ringdowns 0 --driven 1",
        "0 samples per driven run",
    ),
    ("synth --effect none --out o --fps 0.1", "--fps"),
    (
        "synth --effect none --out o --turns 1e5 --samples-per-turn 10000",
        "samples per driven run",
    ),
    (
        "synth --effect none --out o --driven 1000 --turns 1000",
        "at most 2000000",
    ),
    ("synth --effect none --out o --size inf", "size"),
    ("synth --effect none --out {file}", "not a folder"),
    (
        "synth --effect none --out {out-json}",
        "folder `report.json`",
    ),
    // fit
    ("fit {missing}", "experiment.toml"),
    ("fit {set-nan}", "a.csv:3"),
    ("fit {set-back}", "a.csv:4"),
    ("fit {set-kind}", "unknown kind `spin`"),
    ("fit {set-abs}", "relative path"),
    ("fit {set-angle}", "theta_deg"),
    ("fit {set-nofile}", "a.csv"),
    ("fit {set-empty}", "empty file"),
    ("fit {file}", "experiment.toml"),
    ("fit {set-link}", "outside the set's folder"),
    ("fit {set-latin1}", "a.csv:3: byte 0xE9 is not UTF-8"),
    ("fit {set-fhz}", "experiment.toml:10: `f_hz` = 1e300"),
    ("fit {set-f50}", "turns at 0.5 Hz"),
    ("fit {set-deg}", "look like degrees"),
    ("fit {set-r}", "experiment.toml:4"),
    ("diagnose {set-link} --out o", "outside the set's folder"),
    ("fit {set-nan} --tol 0", "`tol` = 0"),
    ("fit {set-nan} --tol 1", "`tol` = 1"),
    // diagnose
    ("diagnose {missing} --out o", "experiment.toml"),
    ("diagnose {set-nan} --out o", "a.csv:3"),
    ("diagnose {set-kind} --out o", "experiment.toml:8"),
    ("diagnose {set-nan} --out {file}", "not a folder"),
    ("diagnose {set-nan}", "--out"),
    ("diagnose {set-nan} --out o --tol nan", "`tol` = NaN"),
    ("diagnose {set-ok} --out {out-json}", "folder `report.json`"),
    ("diagnose {set-ok} --out {out-foreign}", "file `data.csv`"),
    // campaign
    ("campaign", "--out"),
    ("campaign --out o --seeds 0", "seeds"),
    ("campaign --out o --seeds 1000000", "seeds"),
    ("campaign --out o --null-seeds 0", "null-seeds"),
    ("campaign --out o --effects nope", "nope"),
    ("campaign --out o --sizes=-1", "level"),
    ("campaign --out o --sizes nan", "level"),
    ("campaign --out o --tol=-1e-8", "`tol` = -1e-8"),
    ("campaign --out o --set huge", "unknown set size"),
    ("campaign --out o --step 0", "step"),
    ("campaign --out o --step 1", "step"),
    ("campaign --out o --turns nan", "turns"),
    (
        "campaign --out o --ringdowns 0 --driven 0",
        "at least one run",
    ),
    ("campaign --out {file}", "not a folder"),
    (
        "campaign --out o --first-seed 18446744073709551614 --null-seeds 3",
        "largest seed",
    ),
    (
        "campaign --out o --first-seed 18446744073709551615 --seeds 2",
        "largest seed",
    ),
    (
        "campaign --out o --ringdowns 18446744073709551615",
        "ringdowns",
    ),
    ("campaign --out o --turns 1e9", "samples per driven run"),
    ("campaign --out o --turns 0.01", "samples per driven run"),
    // bench-integrators
    ("bench-integrators --event-tols 0", "tol"),
    ("bench-integrators --event-tols 1.5", "tol"),
    ("bench-integrators --event-tols x", "invalid value"),
    ("bench-integrators --fixed-steps 0", "fixed-steps"),
    ("bench-integrators --reg-eps 5", "epsilon"),
    ("bench-integrators --reg-tols nan", "tol"),
    ("bench-integrators --reference-tol 0", "reference-tol"),
    ("bench-integrators --min-time 100", "min-time"),
    ("bench-integrators --periods 1e9", "periods"),
    ("bench-integrators --f 1e300", "`f`"),
    ("bench-integrators --x0-deg 0,inf", "x0"),
    ("bench-integrators --figure wp.jpg", ".svg or .png"),
    ("bench-integrators --csv {dir}", "is a folder"),
];

#[test]
fn every_command_refuses_bad_input_with_exit_2_and_no_output() {
    let fx = Fixtures::new();
    let before = fx.listing();
    let mut failures = Vec::new();
    for (i, (args, needle)) in CASES.iter().enumerate() {
        let cwd = fx.root.join(format!("cwd-{i}"));
        std::fs::create_dir_all(&cwd).unwrap();
        let argv: Vec<String> = args.split_whitespace().map(|a| fx.expand(a)).collect();
        let t = std::time::Instant::now();
        let out = Command::new(env!("CARGO_BIN_EXE_gearbif"))
            .args(&argv)
            .current_dir(&cwd)
            .output()
            .expect("the binary runs");
        let secs = t.elapsed().as_secs_f64();
        let err = String::from_utf8_lossy(&out.stderr);
        let left = listing(&cwd);
        let mut why = Vec::new();
        if out.status.code() != Some(2) {
            why.push(format!("exit {:?}", out.status.code()));
        }
        if !err.to_lowercase().contains(&needle.to_lowercase()) {
            why.push(format!("message lacks `{needle}`"));
        }
        if err.contains("panicked") {
            why.push("panic".into());
        }
        if err.contains("an ordinary file") {
            why.push("quotes a file's content".into());
        }
        if !left.is_empty() {
            why.push(format!("left behind {left:?}"));
        }
        if secs > 5.0 {
            why.push(format!(
                "took {secs:.1} s: the check comes after heavy work"
            ));
        }
        if !why.is_empty() {
            failures.push(format!(
                "`gearbif {args}`: {}\n    stderr: {}",
                why.join(", "),
                err.trim()
            ));
        }
        std::fs::remove_dir_all(&cwd).ok();
    }
    assert_eq!(fx.listing(), before, "a case wrote into the fixtures");
    std::fs::remove_dir_all(&fx.root).ok();
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        CASES.len(),
        failures.join("\n")
    );
}

/// The table covers every command the binary lists in `--help`.
#[test]
fn every_command_has_a_bad_input_case() {
    let out = Command::new(env!("CARGO_BIN_EXE_gearbif"))
        .arg("--help")
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    let commands: Vec<&str> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .collect();
    assert!(commands.len() >= 14, "{commands:?}");
    for c in commands {
        assert!(
            CASES
                .iter()
                .any(|(a, _)| a.split_whitespace().next() == Some(c)),
            "no bad-input case for `{c}`"
        );
    }
}

/// Numeric flags of fast commands set to extreme values, one at a time (a structure-aware fuzz
/// of the command line): each run ends with exit 0 (a valid result) or 2 (a refusal naming the
/// flag), never a panic or a hang. The values span 1e-300 … 1e300 of both signs and the
/// non-finite ones; the hang guard is generous, the runs take well under a second each.
#[test]
fn extreme_numeric_flags_give_a_result_or_exit_2() {
    const VALUES: &[&str] = &[
        "1e-300", "-1e-300", "1e-30", "1e-5", "0", "-1", "7", "1e5", "1e30", "1e300", "-1e300",
        "nan", "inf",
    ];
    // (command with a `{}` slot for the value, the flag's name as errors give it)
    const TEMPLATES: &[(&str, &str)] = &[
        ("info --m1 {}", "m1"),
        ("info --r {}", "`r`|`g`"),
        ("info --inertia {}", "inertia|`g`"),
        ("info --zeta {}", "zeta"),
        ("info --eta {}", "eta"),
        ("info --theta-deg {}", "theta_deg"),
        ("info --f {}", "f"),
        ("map --iterations 3 --f {}", "f"),
        ("map --iterations 3 --zeta {}", "zeta"),
        ("map --iterations 3 --inertia {}", "inertia|`g`"),
        ("simulate --periods 1 --tol {}", "tol"),
        ("simulate --periods {} --samples-per-period 1", "periods"),
        ("simulate --periods 1 --eta {}", "eta"),
        ("classify --settle 2 --record 1 --analysis 2 --f {}", "f"),
        ("classify --settle 2 --record 1 --analysis 2 --beta0-deg {}", "beta0_deg"),
        ("sweep --quiet --settle 1 --record 1 --analysis 0 --rows theta:0:10:10 --cols zeta:0:{}:1", "zeta"),
        ("basins --quiet --cells-beta 2 --cells-omega 2 --samples 2 --no-kick --f {}", "f"),
        ("basins --quiet --cells-beta 2 --cells-omega 2 --samples 2 --no-kick --f 2 --tol {}", "tol"),
    ];
    let root = std::env::temp_dir().join(format!("gearbif-fuzzcli-{}", std::process::id()));
    let mut failures = Vec::new();
    let mut outcomes = [0usize; 2];
    for (template, name) in TEMPLATES {
        for v in VALUES {
            let cmd = template.replace("{}", v);
            let cwd = root.join("cwd");
            let _ = std::fs::remove_dir_all(&cwd);
            std::fs::create_dir_all(&cwd).unwrap();
            let mut child = Command::new(env!("CARGO_BIN_EXE_gearbif"))
                .args(cmd.split_whitespace())
                .current_dir(&cwd)
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap();
            // a hang guard only (the runs take well under a second)
            let t = std::time::Instant::now();
            let status = loop {
                if let Some(s) = child.try_wait().unwrap() {
                    break Some(s);
                }
                if t.elapsed().as_secs() > 60 {
                    let _ = child.kill();
                    child.wait().unwrap();
                    break None;
                }
                std::thread::sleep(std::time::Duration::from_millis(10));
            };
            let mut err = String::new();
            use std::io::Read;
            child.stderr.take().unwrap().read_to_string(&mut err).ok();
            match status.and_then(|s| s.code()) {
                Some(0) => outcomes[0] += 1,
                Some(2) if name.split('|').any(|n| err.contains(n)) || err.contains("Usage") => {
                    outcomes[1] += 1
                }
                Some(2) => failures.push(format!(
                    "`{cmd}`: exit 2 without naming `{name}`: {}",
                    err.trim()
                )),
                None => failures.push(format!("`{cmd}`: did not end (killed by the hang guard)")),
                Some(c) => failures.push(format!("`{cmd}`: exit {c}: {}", err.trim())),
            }
            if err.contains("panicked") {
                failures.push(format!("`{cmd}`: panic: {}", err.trim()));
            }
        }
    }
    std::fs::remove_dir_all(&root).ok();
    eprintln!("{} results, {} refusals", outcomes[0], outcomes[1]);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
