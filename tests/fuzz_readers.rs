//! Fuzzing of every reader of gearbif's input files, as property tests: arbitrary bytes and
//! structure-aware mutations of valid files (truncation, byte flips, deleted, duplicated or swapped
//! lines, numbers replaced by NaN, ±inf, 1e308, …). Every reader must return either a value that
//! satisfies its documented invariants or a typed error naming the file (and the line, where one
//! line is at fault); none may panic.
//!
//! Readers: a run's CSV (`parse_csv`), experiment.toml (`parse_experiment`), a whole recording set
//! from disk (`read_set`, raw bytes including invalid UTF-8), the `--config` TOML (`parse_config`)
//! a sweep's checkpoint (spec.json and row files, through `SweepRunner`) and a sharded sweep's
//! checkpoints (shard.json, spec.json, row files, through `merge_shards`).
//!
//! CI runs a few hundred cases per reader (well under a second each). A long run by hand:
//! `GEARBIF_FUZZ_CASES=200000 cargo test --release --test fuzz_readers` (docs/errors.md).
#![cfg(feature = "cli")]

use gearbif::analysis::ClassifyOptions;
use gearbif::cli::{parse_config, GearConfig};
use gearbif::io::recordings::{parse_csv, parse_experiment, read_set, RunKind};
use gearbif::sweep::{merge_shards, Axis, Shard, SweepOutcome, SweepParam, SweepRunner, SweepSpec};
use gearbif::Error;
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

/// Cases per property: `GEARBIF_FUZZ_CASES` or `default`.
fn cases(default: u32) -> u32 {
    std::env::var("GEARBIF_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

fn config(default: u32) -> ProptestConfig {
    ProptestConfig {
        cases: cases(default),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

fn tmpdir(name: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let d = std::env::temp_dir().join(format!(
        "gearbif-fuzz-{}-{name}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

// ---------------------------------------------------------------------------------------------
// structure-aware mutations

/// Values that readers must not take at face value.
const NASTY: &[&str] = &[
    "NaN",
    "nan",
    "inf",
    "-inf",
    "+inf",
    "1e308",
    "1e309",
    "-1e308",
    "2",
    "7",
    "18446744073709551615",
    "-0",
    "0",
    "-1",
    "1e-320",
    "",
    " ",
    "0x10",
    "1_000",
    "99999999999999999999999",
    "\"x\"",
    "[]",
    "{}",
    "null",
    "true",
    "\u{feff}",
    "\0",
    "\r",
    "#",
    ",",
    "=",
    "[",
    "\"",
    "[[run]]",
    "[gear]",
    "é",
];

/// One edit of a file; positions are fractions of its length (so they apply to any file).
#[derive(Debug, Clone)]
enum Mutation {
    Truncate(f64),
    FlipByte(f64, u8),
    DeleteRange(f64, usize),
    InsertBytes(f64, Vec<u8>),
    InsertNasty(f64, usize),
    ReplaceNumber(f64, usize),
    DeleteLine(f64),
    DuplicateLine(f64),
    SwapLines(f64, f64),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let pos = 0.0..1.0f64;
    prop_oneof![
        pos.clone().prop_map(Mutation::Truncate),
        (pos.clone(), any::<u8>()).prop_map(|(p, b)| Mutation::FlipByte(p, b)),
        (pos.clone(), 1..40usize).prop_map(|(p, n)| Mutation::DeleteRange(p, n)),
        (pos.clone(), proptest::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(p, b)| Mutation::InsertBytes(p, b)),
        (pos.clone(), 0..NASTY.len()).prop_map(|(p, k)| Mutation::InsertNasty(p, k)),
        (pos.clone(), 0..NASTY.len()).prop_map(|(p, k)| Mutation::ReplaceNumber(p, k)),
        pos.clone().prop_map(Mutation::DeleteLine),
        pos.clone().prop_map(Mutation::DuplicateLine),
        (pos.clone(), pos).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
    ]
}

fn at(len: usize, p: f64) -> usize {
    ((len as f64 * p) as usize).min(len)
}

/// Byte ranges of the numbers in `b` (digits with sign, point and exponent).
fn numbers(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() {
            let mut s = i;
            while s > 0 && matches!(b[s - 1], b'-' | b'+' | b'.') {
                s -= 1;
            }
            let mut e = i;
            while e < b.len()
                && (b[e].is_ascii_alphanumeric() || matches!(b[e], b'.' | b'-' | b'+'))
            {
                e += 1;
            }
            out.push((s, e));
            i = e;
        } else {
            i += 1;
        }
    }
    out
}

fn lines(b: &[u8]) -> Vec<Vec<u8>> {
    b.split_inclusive(|&c| c == b'\n')
        .map(<[u8]>::to_vec)
        .collect()
}

fn apply(mut b: Vec<u8>, muts: &[Mutation]) -> Vec<u8> {
    for m in muts {
        let n = b.len();
        match m {
            Mutation::Truncate(p) => b.truncate(at(n, *p)),
            Mutation::FlipByte(p, x) => {
                if n > 0 {
                    let i = at(n - 1, *p);
                    b[i] ^= x | 1;
                }
            }
            Mutation::DeleteRange(p, k) => {
                let i = at(n, *p);
                b.drain(i..(i + k).min(n));
            }
            Mutation::InsertBytes(p, x) => {
                let i = at(n, *p);
                b.splice(i..i, x.iter().copied());
            }
            Mutation::InsertNasty(p, k) => {
                let i = at(n, *p);
                b.splice(i..i, NASTY[*k].bytes());
            }
            Mutation::ReplaceNumber(p, k) => {
                let nums = numbers(&b);
                if !nums.is_empty() {
                    let (s, e) = nums[at(nums.len() - 1, *p)];
                    b.splice(s..e, NASTY[*k].bytes());
                }
            }
            Mutation::DeleteLine(p) | Mutation::DuplicateLine(p) => {
                let mut ls = lines(&b);
                if !ls.is_empty() {
                    let i = at(ls.len() - 1, *p);
                    if matches!(m, Mutation::DeleteLine(_)) {
                        ls.remove(i);
                    } else {
                        let l = ls[i].clone();
                        ls.insert(i, l);
                    }
                    b = ls.concat();
                }
            }
            Mutation::SwapLines(p, q) => {
                let mut ls = lines(&b);
                if !ls.is_empty() {
                    let (i, j) = (at(ls.len() - 1, *p), at(ls.len() - 1, *q));
                    ls.swap(i, j);
                    b = ls.concat();
                }
            }
        }
    }
    b
}

fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    proptest::collection::vec(mutation(), 1..5)
}

/// Checks that `e` is a typed file error naming `file`, with a line inside the text if any.
fn file_error(e: &Error, file: &str, text: &str) -> Result<(), TestCaseError> {
    match e {
        Error::Recording {
            file: f,
            line,
            what,
        } => {
            prop_assert!(f.contains(file), "error names `{}`, not `{}`", f, file);
            prop_assert!(!what.is_empty());
            if let Some(l) = line {
                let n = text.split('\n').count();
                prop_assert!(*l >= 1 && *l <= n, "line {} outside 1..={}", l, n);
            }
            Ok(())
        }
        other => Err(TestCaseError::fail(format!(
            "expected a file error naming {file}, got {other:?}"
        ))),
    }
}

// ---------------------------------------------------------------------------------------------
// valid seed files

const CSV: &str =
    "# a ring-down\nt,alpha,beta\n0.0,0.5,1.0\n0.01,0.5,1.02\n0.02,0.5,1.05\n0.03,0.5,1.04\n";

const EXPERIMENT: &str = r#"# recording set
[gear]
m1 = 3.51
m2 = 3.51
r = 0.04
theta_deg = 31.0
phi_deg = 31.0
inertia = 6.45e-5
theta_tol_deg = 1.0

[[run]]
kind = "ringdown"
alpha0_deg = 30.0
file = "ringdown_01.csv"

[[run]]
kind = "driven"
f_hz = 1.5
file = "driven_01.csv"
"#;

const CONFIG: &str = "# a gear\n[gear]\nm1 = 3.51\nm2 = 3.51\nr = 0.04\ninertia = 6.45e-5\ntheta_deg = 25.0\nphi_deg = 20.0\nzeta = 1.1\neta = 23.1\n";

fn check_csv(text: &str) -> Result<(), TestCaseError> {
    match parse_csv(text, "run.csv") {
        Ok(c) => {
            prop_assert!(!c.t.is_empty());
            prop_assert!(c.t.len() == c.alpha.len() && c.t.len() == c.beta.len());
            prop_assert!(c.t.windows(2).all(|w| w[1] > w[0]));
            prop_assert!(c
                .t
                .iter()
                .chain(&c.alpha)
                .chain(&c.beta)
                .all(|x| x.is_finite()));
            Ok(())
        }
        Err(e) => file_error(&e, "run.csv", text),
    }
}

fn check_experiment(text: &str) -> Result<(), TestCaseError> {
    match parse_experiment(text, "experiment.toml") {
        Ok((gear, runs)) => {
            prop_assert!(!runs.is_empty());
            for v in [gear.m1, gear.m2, gear.r] {
                prop_assert!(v.is_finite() && v > 0.0);
            }
            for v in [gear.theta_deg, gear.phi_deg] {
                prop_assert!(v.is_finite() && v.abs() <= 360.0);
            }
            for r in &runs {
                prop_assert!(!r.file.is_empty() && !Path::new(&r.file).is_absolute());
                prop_assert!(!r.file.split(['/', '\\']).any(|c| c == ".."));
                match r.kind {
                    RunKind::Driven { f_hz } => prop_assert!((1e-3..=1e4).contains(&f_hz)),
                    RunKind::Ringdown { alpha0 } => {
                        prop_assert!(alpha0.abs() <= 360f64.to_radians() + 1e-12)
                    }
                }
            }
            Ok(())
        }
        Err(e) => file_error(&e, "experiment.toml", text),
    }
}

fn check_config(text: &str) -> Result<(), TestCaseError> {
    match parse_config(text, "gear.toml") {
        Ok(g) => {
            let GearConfig {
                m1,
                m2,
                r,
                inertia,
                theta_deg,
                phi_deg,
                zeta,
                eta,
                ..
            } = g;
            for v in [m1, m2, r, inertia].into_iter().flatten() {
                prop_assert!(v.is_finite() && v > 0.0);
            }
            for v in [zeta, eta].into_iter().flatten() {
                prop_assert!(v.is_finite() && v >= 0.0);
            }
            for v in [theta_deg, phi_deg].into_iter().flatten() {
                prop_assert!(v.is_finite() && v.abs() <= 360.0);
            }
            Ok(())
        }
        Err(e) => file_error(&e, "gear.toml", text),
    }
}

#[test]
fn seeds_are_valid() {
    assert_eq!(parse_csv(CSV, "run.csv").unwrap().t.len(), 4);
    assert_eq!(parse_experiment(EXPERIMENT, "e.toml").unwrap().1.len(), 2);
    assert_eq!(parse_config(CONFIG, "g.toml").unwrap().phi_deg, Some(20.0));
}

proptest! {
    #![proptest_config(config(512))]

    #[test]
    fn csv_arbitrary_text(s in "\\PC{0,300}") {
        check_csv(&s)?;
    }

    #[test]
    fn csv_mutated(m in mutations()) {
        let b = apply(CSV.as_bytes().to_vec(), &m);
        check_csv(&String::from_utf8_lossy(&b))?;
    }

    #[test]
    fn experiment_arbitrary_text(s in "\\PC{0,300}") {
        check_experiment(&s)?;
    }

    #[test]
    fn experiment_mutated(m in mutations()) {
        let b = apply(EXPERIMENT.as_bytes().to_vec(), &m);
        check_experiment(&String::from_utf8_lossy(&b))?;
    }

    /// One number of experiment.toml replaced by ±m·10^e, e in -300..=300: a set in the
    /// documented domains or an error naming the file and the line.
    #[test]
    fn experiment_numbers_across_the_exponent_range(
        which in 0..64usize,
        m in 1.0..10.0f64,
        e in -300..=300i32,
        negative in any::<bool>(),
    ) {
        let nums = numbers(EXPERIMENT.as_bytes());
        let (a, b) = nums[which % nums.len()];
        let v = format!("{}{m}e{e}", if negative { "-" } else { "" });
        let text = format!("{}{v}{}", &EXPERIMENT[..a], &EXPERIMENT[b..]);
        check_experiment(&text)?;
    }

    #[test]
    fn config_arbitrary_text(s in "\\PC{0,300}") {
        check_config(&s)?;
    }

    #[test]
    fn config_mutated(m in mutations()) {
        let b = apply(CONFIG.as_bytes().to_vec(), &m);
        check_config(&String::from_utf8_lossy(&b))?;
    }
}

// ---------------------------------------------------------------------------------------------
// files on disk: raw bytes (invalid UTF-8 included) through read_set

proptest! {
    #![proptest_config(config(128))]

    #[test]
    fn recording_set_from_raw_bytes(
        me in mutations(),
        mc in mutations(),
        raw in proptest::option::of(proptest::collection::vec(any::<u8>(), 0..200)),
    ) {
        let dir = tmpdir("set");
        let exp = raw.clone().unwrap_or_else(|| apply(EXPERIMENT.as_bytes().to_vec(), &me));
        std::fs::write(dir.join("experiment.toml"), &exp).unwrap();
        std::fs::write(dir.join("ringdown_01.csv"), apply(CSV.as_bytes().to_vec(), &mc)).unwrap();
        std::fs::write(dir.join("driven_01.csv"), CSV).unwrap();
        let r = read_set(&dir);
        std::fs::remove_dir_all(&dir).ok();
        match r {
            Ok(set) => {
                prop_assert!(!set.runs.is_empty());
                for run in &set.runs {
                    prop_assert!(run.t.iter().chain(&run.alpha).chain(&run.beta).all(|x| x.is_finite()));
                }
            }
            Err(Error::Recording { file, what, .. }) => {
                prop_assert!(file.ends_with("experiment.toml") || file.ends_with(".csv"), "{}", file);
                prop_assert!(!what.is_empty());
            }
            Err(e) => prop_assert!(false, "untyped error {:?}", e),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// sweep checkpoints

/// A tiny sweep (2 rows × 2 columns, short settling) and the files of its finished checkpoint.
fn checkpoint_seed() -> &'static (SweepSpec, Vec<u8>, Vec<u8>) {
    static SEED: OnceLock<(SweepSpec, Vec<u8>, Vec<u8>)> = OnceLock::new();
    SEED.get_or_init(|| {
        let mut spec = SweepSpec::paper_fig7(
            Axis::range(SweepParam::ThetaDeg, 20.0, 30.0, 10.0).unwrap(),
            Axis::range(SweepParam::F, 1.0, 1.5, 0.5).unwrap(),
        );
        spec.classify = ClassifyOptions {
            settle_turns: 2,
            record_turns: 1,
            rigorous: false,
            ..ClassifyOptions::default()
        };
        let dir = tmpdir("ckpt-seed");
        let out = SweepRunner::new(spec.clone())
            .checkpoint(&dir)
            .run()
            .unwrap();
        assert!(matches!(out, SweepOutcome::Complete(_)));
        let spec_json = std::fs::read(dir.join("spec.json")).unwrap();
        let row = std::fs::read(dir.join("rows/row-00000.json")).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        (spec, spec_json, row)
    })
}

proptest! {
    #![proptest_config(config(128))]

    /// A damaged spec.json is refused with its file and line; a damaged row file is never taken:
    /// the row counts as not done (and would be recomputed).
    #[test]
    fn checkpoint_files_mutated(
        ms in proptest::option::of(mutations()),
        mr in proptest::option::of(mutations()),
    ) {
        let (spec, spec_json, row) = checkpoint_seed();
        let dir = tmpdir("ckpt");
        let spec_b = ms.as_ref().map_or(spec_json.clone(), |m| apply(spec_json.clone(), m));
        let row_b = mr.as_ref().map_or(row.clone(), |m| apply(row.clone(), m));
        std::fs::write(dir.join("spec.json"), &spec_b).unwrap();
        std::fs::create_dir_all(dir.join("rows")).unwrap();
        std::fs::write(dir.join("rows/row-00000.json"), &row_b).unwrap();
        let r = SweepRunner::new(spec.clone()).checkpoint(&dir).max_new_rows(0).run();
        std::fs::remove_dir_all(&dir).ok();
        match r {
            Ok(SweepOutcome::Stopped { rows_done, rows_total }) => {
                prop_assert_eq!(rows_total, 2);
                prop_assert!(rows_done <= 1);
                if rows_done == 1 {
                    // only a row that still deserialises to the same indices and values is taken
                    let back: gearbif::sweep::RowResult = serde_json::from_slice(&row_b).unwrap();
                    prop_assert_eq!(back.row, 0);
                    prop_assert_eq!(back.points.len(), 2);
                }
            }
            Ok(SweepOutcome::Complete(_)) => prop_assert!(false, "row 1 was never computed"),
            Err(Error::Recording { file, line, .. }) => {
                prop_assert!(file.ends_with("spec.json"), "{}", file);
                prop_assert!(line.is_some());
            }
            Err(Error::Checkpoint { reason, .. }) => {
                prop_assert!(reason.contains("different sweep"), "{}", reason)
            }
            Err(e) => prop_assert!(false, "untyped error {:?}", e),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// sweep shards (`sweep --shard i/N` checkpoints, read back by `sweep merge`)

/// The two shard checkpoints (0/2 and 1/2) of the tiny sweep, as (relative path, bytes).
fn shard_seed() -> &'static Vec<(String, Vec<u8>)> {
    static SEED: OnceLock<Vec<(String, Vec<u8>)>> = OnceLock::new();
    SEED.get_or_init(|| {
        let (spec, _, _) = checkpoint_seed();
        let dir = tmpdir("shard-seed");
        let mut files = Vec::new();
        for i in 0..2 {
            let d = dir.join(format!("s{i}"));
            let st = SweepRunner::new(spec.clone())
                .checkpoint(&d)
                .run_shard(Shard::new(i, 2).unwrap())
                .unwrap();
            assert!(st.complete());
            for f in ["spec.json", "shard.json", &format!("rows/row-{i:05}.json")] {
                files.push((format!("s{i}/{f}"), std::fs::read(d.join(f)).unwrap()));
            }
        }
        std::fs::remove_dir_all(&dir).ok();
        files
    })
}

proptest! {
    #![proptest_config(config(128))]

    /// Damaged shard files (manifest, spec, row) make `merge` refuse with a typed error naming the
    /// file, never panic; an undamaged set merges to the sweep's two rows.
    #[test]
    fn shard_files_mutated(which in 0..6usize, m in mutations()) {
        let files = shard_seed();
        let dir = tmpdir("shard");
        for (k, (name, bytes)) in files.iter().enumerate() {
            let p = dir.join(name);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            let b = if k == which { apply(bytes.clone(), &m) } else { bytes.clone() };
            std::fs::write(p, b).unwrap();
        }
        let r = merge_shards(&[dir.join("s0"), dir.join("s1")]);
        std::fs::remove_dir_all(&dir).ok();
        match r {
            Ok(res) => {
                prop_assert_eq!(res.rows.len(), 2);
                for (i, row) in res.rows.iter().enumerate() {
                    prop_assert_eq!(row.row, i);
                    prop_assert_eq!(row.points.len(), 2);
                }
            }
            Err(Error::Recording { file, .. }) => {
                prop_assert!(file.ends_with(".json"), "{}", file);
            }
            // a file that does not parse: the format error names it, the JSON error its line
            Err(Error::Format { what, source, .. }) => {
                prop_assert!(what.ends_with(".json"), "{}", what);
                let s = source.to_string();
                prop_assert!(s.contains("line") || s.contains("UTF-8") || s.contains("utf-8"), "{}", s);
            }
            Err(Error::File { path, .. }) => prop_assert!(path.ends_with(".json"), "{}", path),
            // a file that parses but does not fit the others: the folder or file is named
            Err(Error::Checkpoint { path, .. }) => prop_assert!(!path.is_empty()),
            Err(e) => prop_assert!(false, "untyped error {:?}", e),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// regressions found by the fuzzers

/// Shard manifests whose shard is impossible (count 0, index beyond count, a count no sweep of
/// these rows can have) are refused; before, `merge` indexed out of bounds or tried to allocate
/// 2^64 slots.
#[test]
fn impossible_shard_manifests_are_refused() {
    let files = shard_seed();
    let manifest = &files.iter().find(|(n, _)| n == "s0/shard.json").unwrap().1;
    let manifest = String::from_utf8(manifest.clone()).unwrap();
    let count = manifest
        .find("\"count\": 2")
        .expect("count in the manifest");
    let index = manifest
        .find("\"index\": 0")
        .expect("index in the manifest");
    for (what, at) in [
        ("\"count\": 0", count),
        ("\"index\": 5", index),
        ("\"count\": 18446744073709551615", count),
        ("\"count\": 3", count),
    ] {
        let mut m = manifest.clone();
        m.replace_range(at..at + 10, what);
        let dir = tmpdir("shard-manifest");
        for (name, bytes) in files {
            let p = dir.join(name);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            let b = if name == "s0/shard.json" {
                m.as_bytes()
            } else {
                bytes
            };
            std::fs::write(p, b).unwrap();
        }
        let r = merge_shards(&[dir.join("s0"), dir.join("s1")]);
        std::fs::remove_dir_all(&dir).ok();
        match r {
            Err(Error::Checkpoint { path, reason }) => {
                assert!(path.ends_with("shard.json"), "{what}: {path}: {reason}")
            }
            other => panic!("{what}: expected a refusal naming shard.json, got {other:?}"),
        }
    }
}

#[test]
fn run_files_outside_the_set_folder_are_refused() {
    for f in ["/dev/zero", "../x.csv", "a/../../x.csv"] {
        let t = EXPERIMENT.replace("ringdown_01.csv", f);
        let e = parse_experiment(&t, "experiment.toml").unwrap_err();
        assert!(e.to_string().contains("relative path"), "{f}: {e}");
        assert!(e.to_string().contains("experiment.toml:11"), "{f}: {e}");
    }
}

#[test]
fn angles_beyond_a_turn_are_refused_with_their_line() {
    let t = EXPERIMENT.replace("theta_deg = 31.0", "theta_deg = 1e308");
    let e = parse_experiment(&t, "experiment.toml").unwrap_err();
    assert!(e.to_string().contains("theta_deg"), "{e}");
    let c = CONFIG.replace("phi_deg = 20.0", "phi_deg = -400");
    let e = parse_config(&c, "gear.toml").unwrap_err();
    assert_eq!(
        e.to_string(),
        "gear.toml:8: [gear]: phi_deg = -400 must be finite and in [-360, 360]"
    );
}
