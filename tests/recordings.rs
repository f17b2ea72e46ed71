//! The recording-set reader: round trip, every documented error (file, line, what), and property
//! tests that no input crashes it.

use gearbif::identification::synth::{synthesize, SynthOptions};
use gearbif::io::recordings::{parse_csv, parse_experiment, read_set, unwrap, write_set};
use gearbif::Error;
use proptest::prelude::*;
use std::path::PathBuf;

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gearbif-rec-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const GEAR: &str = "[gear]\nm1 = 3.51\nm2 = 3.51\nr = 0.04\ntheta_deg = 31.0\nphi_deg = 31.0\n";

fn expect_rec(e: Error, file_part: &str, line: Option<usize>, what_part: &str) {
    match e {
        Error::Recording {
            file,
            line: l,
            what,
        } => {
            assert!(file.contains(file_part), "file {file}");
            assert_eq!(l, line, "line for {what}");
            assert!(what.contains(what_part), "what: {what}");
        }
        other => panic!("expected a recording error, got {other:?}"),
    }
}

#[test]
fn round_trip_with_wrapped_angles_unwraps() {
    let o = SynthOptions {
        ringdowns: 2,
        driven: 2,
        turns: 6.0,
        f_range: (1.0, 2.5),
        ..SynthOptions::default()
    };
    let (set, _) = synthesize(&o).unwrap();
    let dir = tmpdir("rt");
    write_set(&set, &dir, true).unwrap();
    let back = read_set(&dir).unwrap();
    assert_eq!(back.runs.len(), set.runs.len());
    for (a, b) in set.runs.iter().zip(&back.runs) {
        assert_eq!(a.kind, b.kind);
        assert_eq!(a.t.len(), b.t.len());
        // unwrapped up to a common multiple of 2π
        let k = ((a.beta[0] - b.beta[0]) / std::f64::consts::TAU).round();
        for i in 0..a.t.len() {
            let d = a.beta[i] - b.beta[i] - k * std::f64::consts::TAU;
            assert!(d.abs() < 1e-5, "{} sample {i}: {d}", a.file);
        }
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn csv_errors_name_file_line_and_what() {
    expect_rec(
        parse_csv("t,alpha\n0,1\n", "a.csv").unwrap_err(),
        "a.csv",
        Some(1),
        "missing column `beta`",
    );
    expect_rec(
        parse_csv("t,alpha,beta\n0,0,0\n0.1,0,NaN\n", "b.csv").unwrap_err(),
        "b.csv",
        Some(3),
        "not finite",
    );
    expect_rec(
        parse_csv("# c\nt,alpha,beta\n0,0,0\n0.1,0,0\n0.1,0,0\n", "c.csv").unwrap_err(),
        "c.csv",
        Some(5),
        "time not increasing",
    );
    expect_rec(
        parse_csv("t,alpha,beta\n0,0,x\n", "d.csv").unwrap_err(),
        "d.csv",
        Some(2),
        "not a number",
    );
    expect_rec(
        parse_csv("t,alpha,beta\n0,0\n", "e.csv").unwrap_err(),
        "e.csv",
        Some(2),
        "fields",
    );
    expect_rec(
        parse_csv("t,alpha,beta\n# only a comment\n", "f.csv").unwrap_err(),
        "f.csv",
        None,
        "run without samples",
    );
    // extra columns and any column order are fine
    let c = parse_csv("beta,t,x,alpha\n1,0,9,2\n3,0.5,9,4\n", "g.csv").unwrap();
    assert_eq!(c.t, vec![0.0, 0.5]);
    assert_eq!(c.beta, vec![1.0, 3.0]);
}

#[test]
fn experiment_errors_name_file_line_and_what() {
    let unknown = format!("{GEAR}\n[[run]]\nkind = \"spin\"\nfile = \"a.csv\"\n");
    expect_rec(
        parse_experiment(&unknown, "experiment.toml").unwrap_err(),
        "experiment.toml",
        Some(8),
        "unknown kind `spin`",
    );
    let nofreq = format!("{GEAR}\n[[run]]\nkind = \"ringdown\"\nalpha0_deg = 3\nfile = \"a.csv\"\n\n[[run]]\nkind = \"driven\"\nfile = \"b.csv\"\n");
    expect_rec(
        parse_experiment(&nofreq, "experiment.toml").unwrap_err(),
        "experiment.toml",
        Some(13),
        "without `f_hz`",
    );
    expect_rec(
        parse_experiment("[gear]\nm1 = 1\n", "x.toml").unwrap_err(),
        "x.toml",
        Some(1),
        "[gear]",
    );
    expect_rec(
        parse_experiment("[gear\n", "y.toml").unwrap_err(),
        "y.toml",
        Some(1),
        "invalid TOML",
    );
    expect_rec(
        parse_experiment(GEAR, "z.toml").unwrap_err(),
        "z.toml",
        None,
        "no [[run]]",
    );
}

#[test]
fn missing_run_file_is_reported_with_its_run_line() {
    let dir = tmpdir("missing");
    let exp = format!("{GEAR}\n[[run]]\nkind = \"driven\"\nf_hz = 1.0\nfile = \"nope.csv\"\n");
    std::fs::write(dir.join("experiment.toml"), exp).unwrap();
    expect_rec(
        read_set(&dir).unwrap_err(),
        "experiment.toml",
        Some(8),
        "nope.csv",
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn unwrap_removes_jumps() {
    let raw = [3.0, -3.1, -2.9, 3.05, 0.0];
    let u = unwrap(&raw);
    for w in u.windows(2) {
        assert!((w[1] - w[0]).abs() <= std::f64::consts::PI);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, .. ProptestConfig::default() })]

    #[test]
    fn csv_reader_never_panics_on_arbitrary_text(s in "\\PC{0,400}") {
        let _ = parse_csv(&s, "p.csv");
    }

    #[test]
    fn csv_reader_never_panics_on_csv_like_text(
        rows in proptest::collection::vec(
            (prop_oneof![Just("0.1".to_string()), Just("NaN".to_string()), Just("inf".to_string()),
                         Just("".to_string()), Just("-1e308".to_string()), "[-+]?[0-9]{0,3}\\.?[0-9]{0,3}(e[-+]?[0-9]{1,3})?"],
             "[-+]?[0-9]{0,2}\\.?[0-9]{0,4}", "[a-z0-9.#, ]{0,6}"),
            0..40),
        header in prop_oneof![Just("t,alpha,beta"), Just("beta,alpha,t"), Just("t,beta"), Just("# x"), Just("")],
    ) {
        let mut s = String::from(header);
        s.push('\n');
        for (a, b, c) in rows {
            s.push_str(&format!("{a},{b},{c}\n"));
        }
        match parse_csv(&s, "q.csv") {
            Ok(c) => {
                prop_assert!(!c.t.is_empty());
                prop_assert!(c.t.windows(2).all(|w| w[1] > w[0]));
                prop_assert!(c.t.iter().chain(&c.alpha).chain(&c.beta).all(|x| x.is_finite()));
            }
            Err(Error::Recording { file, .. }) => prop_assert_eq!(file, "q.csv"),
            Err(e) => prop_assert!(false, "unexpected error type {:?}", e),
        }
    }

    #[test]
    fn experiment_reader_never_panics(s in "\\PC{0,300}", kind in "[a-z]{0,9}", x in proptest::num::f64::ANY) {
        let _ = parse_experiment(&s, "e.toml");
        let t = format!("{GEAR}\n[[run]]\nkind = \"{kind}\"\nf_hz = {x:?}\nalpha0_deg = {x:?}\nfile = \"a.csv\"\n");
        let _ = parse_experiment(&t, "e.toml");
    }

    #[test]
    fn unwrap_is_continuous_and_congruent(v in proptest::collection::vec(-10.0f64..10.0, 0..50)) {
        let u = unwrap(&v);
        prop_assert_eq!(u.len(), v.len());
        for i in 0..v.len() {
            let k = (u[i] - v[i]) / std::f64::consts::TAU;
            prop_assert!((k - k.round()).abs() < 1e-9);
            if i > 0 {
                prop_assert!((u[i] - u[i - 1]).abs() <= std::f64::consts::PI + 1e-9);
            }
        }
    }
}

#[test]
fn diagnosis_of_degenerate_sets_errs_without_panicking() {
    use gearbif::identification::diagnose::{diagnose, DiagnoseOptions};
    use gearbif::io::recordings::{GearSetup, RecordingSet, Run, RunKind};
    let run = |n: usize, kind: RunKind| Run {
        kind,
        file: format!("r{n}.csv"),
        t: (0..n).map(|i| i as f64 * 0.01).collect(),
        alpha: vec![0.3; n],
        beta: vec![1.0; n],
    };
    for runs in [
        vec![run(1, RunKind::Ringdown { alpha0: 0.3 })],
        vec![
            run(5, RunKind::Driven { f_hz: 1.0 }),
            run(40, RunKind::Ringdown { alpha0: 1.0 }),
        ],
        vec![run(300, RunKind::Ringdown { alpha0: 0.3 })],
    ] {
        let set = RecordingSet {
            dir: PathBuf::new(),
            gear: GearSetup::paper(),
            runs,
        };
        let r = diagnose(
            &set,
            &DiagnoseOptions::default(),
            &gearbif::progress::Silent,
        );
        assert!(r.is_err(), "a set without motion cannot be diagnosed");
    }
}

/// A byte-order mark (as spreadsheet programs write) is not part of the header or the TOML.
#[test]
fn a_byte_order_mark_is_skipped() {
    let c = parse_csv("\u{feff}t,alpha,beta\n0,0,0\n0.1,0,1\n", "bom.csv").unwrap();
    assert_eq!(c.t, [0.0, 0.1]);
    let exp = format!("\u{feff}{GEAR}\n[[run]]\nkind = \"driven\"\nf_hz = 1.0\nfile = \"a.csv\"\n");
    parse_experiment(&exp, "experiment.toml").unwrap();
}

/// The keys experiment.toml may hold but the reader does not know are named with their lines.
#[test]
fn ignored_keys_are_named_with_their_lines() {
    let exp = "[gear]\nm1 = 3.51\nzetta = 1.1\n\n[[run]]\nkind = \"driven\"\nf_hz = 1.0\nfreq = 2\nfile = \"a.csv\"\n";
    let keys = gearbif::io::recordings::ignored_keys(exp);
    assert_eq!(
        keys,
        ["`zetta` in [gear] (line 3)", "`freq` in [[run]] 1 (line 8)"]
    );
    assert!(gearbif::io::recordings::ignored_keys(&format!("{GEAR}\n")).is_empty());
}

/// A run has at most `RUN_SAMPLES_MAX` samples: the next is refused with its line.
#[test]
fn a_run_beyond_the_sample_limit_is_refused_with_its_line() {
    use gearbif::io::recordings::limits::RUN_SAMPLES_MAX;
    let mut text = String::from("t,alpha,beta\n");
    for k in 0..=RUN_SAMPLES_MAX {
        text += &format!("{k},0,0\n");
    }
    match parse_csv(&text, "big.csv").unwrap_err() {
        Error::Recording { line, .. } => assert_eq!(line, Some(RUN_SAMPLES_MAX + 2)),
        e => panic!("{e}"),
    }
}
