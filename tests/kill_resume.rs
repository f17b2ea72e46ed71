//! A sweep killed with SIGKILL at random moments, again and again, then resumed, ends with files
//! bit-identical to an uninterrupted run; after every kill each checkpoint file on disk is whole
//! (atomic writes: a temporary file renamed into place). A damaged row file is recomputed and a
//! damaged spec.json is refused, both without being taken as data.
//!
//! The kill moments come from a fixed seed (`GEARBIF_KILL_SEED` to vary it, `GEARBIF_KILLS` for the
//! number of kills, default 15).
#![cfg(all(feature = "cli", unix))]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

const SWEEP: &[&str] = &[
    "sweep",
    "--quiet",
    "--rows",
    "theta:0:45:5",
    "--cols",
    "f:0.8:1.6:0.4",
    "--settle",
    "400",
    "--record",
    "2",
    "--analysis",
    "0",
    "--tol",
    "1e-8",
];

/// Rows of the sweep (theta from 0 to 45 in steps of 5).
const ROWS: usize = 10;

fn sweep(out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_gearbif"));
    c.args(SWEEP)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    c
}

fn run_to_end(out: &Path) {
    let o = sweep(out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gearbif-kill-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// xorshift64*: reproducible kill moments without a dependency.
struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Every checkpoint file visible under its final name parses (no half-written file is exposed).
fn checkpoint_files_are_whole(out: &Path) -> usize {
    let ck = out.join("checkpoint");
    let mut n = 0;
    if let Ok(b) = std::fs::read(ck.join("spec.json")) {
        serde_json::from_slice::<serde_json::Value>(&b).expect("spec.json is whole");
    }
    if let Ok(rd) = std::fs::read_dir(ck.join("rows")) {
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().to_string();
            if name.starts_with("row-") {
                let b = std::fs::read(e.path()).unwrap();
                serde_json::from_slice::<serde_json::Value>(&b)
                    .unwrap_or_else(|err| panic!("{name} is half-written: {err}"));
                n += 1;
            }
        }
    }
    for f in ["points.csv", "sweep.json"] {
        if let Ok(b) = std::fs::read(out.join(f)) {
            assert!(b.ends_with(b"\n") || b.ends_with(b"}"), "{f} is cut short");
        }
    }
    n
}

fn same_files(a: &Path, b: &Path) {
    for f in ["points.csv", "sweep.json", "rms_map.svg", "complete.json"] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(x == y, "{f} differs from the uninterrupted run");
    }
}

/// The environment variable `name` parsed, else `default` (the kill tests' seed and count).
fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

#[test]
fn killed_and_resumed_sweep_is_bit_identical() {
    let root = tmpdir("sweep");
    let (reference, killed) = (root.join("reference"), root.join("killed"));
    let t = Instant::now();
    run_to_end(&reference);
    let t_ref = t.elapsed();
    let (seed, kills) = (
        env_or("GEARBIF_KILL_SEED", 0x5eed_u64),
        env_or("GEARBIF_KILLS", 15),
    );
    let mut rng = Rng(seed | 1);
    let (mut killed_mid_run, mut rows_seen) = (0, Vec::new());
    let mut scale = t_ref;
    for _ in 0..kills {
        let mut child = sweep(&killed).spawn().unwrap();
        // random moments over what is left of the run: start-up, loading, computing, writing
        let left = 1.0 - rows_seen.last().copied().unwrap_or(0) as f64 / ROWS as f64;
        let delay = scale.mul_f64((0.05 + left) * rng.uniform());
        std::thread::sleep(delay);
        if child.try_wait().unwrap().is_none() {
            child.kill().unwrap(); // SIGKILL
            killed_mid_run += 1;
        } else {
            // the run was faster than the reference (a quieter machine): aim earlier
            scale = scale.mul_f64(0.5);
        }
        child.wait().unwrap();
        rows_seen.push(checkpoint_files_are_whole(&killed));
    }
    run_to_end(&killed);
    same_files(&reference, &killed);
    eprintln!(
        "seed {seed:#x}: {killed_mid_run} of {kills} runs killed mid-run (uninterrupted run {:.2} s); rows checkpointed after each kill: {rows_seen:?}",
        t_ref.as_secs_f64()
    );
    assert!(
        killed_mid_run >= kills / 2,
        "too few kills landed mid-run: {killed_mid_run}"
    );
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn damaged_checkpoint_rows_are_recomputed_and_a_damaged_spec_is_refused() {
    let root = tmpdir("damaged");
    let (reference, damaged) = (root.join("reference"), root.join("damaged"));
    run_to_end(&reference);
    run_to_end(&damaged);
    let rows = damaged.join("checkpoint/rows");
    // a row cut in half (as a non-atomic writer would leave it), a row of another sweep, and a
    // temporary file of a killed writer
    let r3 = rows.join("row-00003.json");
    let b = std::fs::read(&r3).unwrap();
    std::fs::write(&r3, &b[..b.len() / 2]).unwrap();
    std::fs::copy(rows.join("row-00001.json"), rows.join("row-00002.json")).unwrap();
    std::fs::write(rows.join(".row-00004.json.tmp-999999999"), "{\"row\": 4, ").unwrap();
    for f in ["points.csv", "sweep.json", "rms_map.svg"] {
        std::fs::remove_file(damaged.join(f)).unwrap();
    }
    run_to_end(&damaged);
    same_files(&reference, &damaged);
    assert!(!rows.join(".row-00004.json.tmp-999999999").exists());
    // a damaged spec.json: refused, exit code 2, the message names the file and its line
    let spec = damaged.join("checkpoint/spec.json");
    let b = std::fs::read(&spec).unwrap();
    std::fs::write(&spec, &b[..b.len() - 10]).unwrap();
    let o = sweep(&damaged).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("spec.json:") && err.contains("corrupt sweep checkpoint"),
        "{err}"
    );
    std::fs::remove_dir_all(&root).ok();
}

/// Every file under `dir` (relative path → bytes; in text outputs the lines stating computing
/// times, which differ from run to run, are left out).
fn snapshot(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    files(dir, true)
}

/// Every file under `dir` as it is (`normalise`: as [`snapshot`]).
fn files(dir: &Path, normalise: bool) -> std::collections::BTreeMap<String, Vec<u8>> {
    fn walk(
        base: &Path,
        d: &Path,
        normalise: bool,
        out: &mut std::collections::BTreeMap<String, Vec<u8>>,
    ) {
        if let Ok(rd) = std::fs::read_dir(d) {
            for e in rd.flatten() {
                let p = e.path();
                if p.is_dir() {
                    walk(base, &p, normalise, out);
                } else {
                    let rel = p.strip_prefix(base).unwrap().display().to_string();
                    let mut bytes = std::fs::read(&p).unwrap();
                    if normalise && (rel.ends_with(".md") || rel.ends_with(".json")) {
                        let text = String::from_utf8(bytes).unwrap();
                        bytes = text
                            .lines()
                            .filter(|l| !l.contains("Computing time") && !l.contains("seconds"))
                            .collect::<Vec<_>>()
                            .join("\n")
                            .into_bytes();
                    }
                    out.insert(rel, bytes);
                }
            }
        }
    }
    let mut out = std::collections::BTreeMap::new();
    walk(dir, dir, normalise, &mut out);
    out
}

fn gearbif(args: &[&str], out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_gearbif"));
    c.args(args)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    c
}

fn run_ok(args: &[&str], out: &Path) {
    let o = gearbif(args, out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Writes the files of `snap` as the folder `dir` (replacing it).
fn restore(dir: &Path, snap: &std::collections::BTreeMap<String, Vec<u8>>) {
    let _ = std::fs::remove_dir_all(dir);
    for (rel, bytes) in snap {
        let p = dir.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }
}

/// `args_b` run into a folder holding the result of `args_a`, killed at random moments: after
/// every kill the folder holds the earlier result or the new one, whole, and beside it nothing
/// but hidden temporaries of the killed runs, which the next complete run removes.
fn killed_writer_leaves_one_whole_result(name: &str, args_a: &[&str], args_b: &[&str]) {
    let root = tmpdir(name);
    let (out, b) = (root.join("out"), root.join("b"));
    run_ok(args_a, &out);
    let snap_a = snapshot(&out);
    let files_a = files(&out, false);
    let t = Instant::now();
    run_ok(args_b, &b);
    let t_b = t.elapsed();
    let snap_b = snapshot(&b);
    assert_ne!(snap_a, snap_b, "the two results must differ");
    let (seed, kills) = (
        env_or("GEARBIF_KILL_SEED", 0x5eed_u64),
        env_or("GEARBIF_KILLS", 4),
    );
    let mut rng = Rng(seed | 1);
    let (mut old, mut new) = (0, 0);
    for _ in 0..kills {
        let mut child = gearbif(args_b, &out).spawn().unwrap();
        // late moments weigh more: the final writes are what this test is about
        let u = rng.uniform().sqrt();
        std::thread::sleep(t_b.mul_f64(0.3 + 0.9 * u));
        let _ = child.kill();
        child.wait().unwrap();
        let now = snapshot(&out);
        if now == snap_a {
            old += 1;
        } else if now == snap_b {
            new += 1;
            restore(&out, &files_a);
        } else if !out.exists() {
            // killed between moving the earlier result aside and the new one into place: the
            // next run puts the earlier one back; here it is restored by hand
            old += 1;
            restore(&out, &files_a);
        } else {
            let differ = |snap: &std::collections::BTreeMap<String, Vec<u8>>| {
                let mut d: Vec<String> = now
                    .keys()
                    .filter(|k| snap.get(*k) != now.get(*k))
                    .cloned()
                    .collect();
                d.extend(snap.keys().filter(|k| !now.contains_key(*k)).cloned());
                d
            };
            panic!(
                "{name}: after a kill the folder is neither result: it differs from the earlier \
                 one in {:?}, from the new one in {:?}",
                differ(&snap_a),
                differ(&snap_b)
            );
        }
        for e in std::fs::read_dir(&root).unwrap().flatten() {
            let n = e.file_name().to_string_lossy().to_string();
            assert!(
                n == "out" || n == "b" || n.starts_with(".out.tmp-") || n.starts_with(".out.old-"),
                "{name}: a kill left {n} beside the folder"
            );
        }
    }
    run_ok(args_b, &out);
    assert!(snapshot(&out) == snap_b, "{name}: the complete run differs");
    let left: Vec<String> = std::fs::read_dir(&root)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n != "out" && n != "b")
        .collect();
    assert!(left.is_empty(), "{name}: temporaries left: {left:?}");
    eprintln!(
        "{name}: seed {seed:#x}, {kills} kills (run {:.2} s): earlier result {old} times, new {new}",
        t_b.as_secs_f64()
    );
    std::fs::remove_dir_all(&root).ok();
}

/// `diagnose` killed while it replaces an earlier diagnosis of another set (tiny sets, a few
/// seconds each): the folder holds one whole result after every kill.
#[test]
fn killed_diagnose_leaves_one_whole_result() {
    let root = tmpdir("diagnose-sets");
    let set = |name: &str, seed: &str| {
        let p = root.join(name);
        let o = Command::new(env!("CARGO_BIN_EXE_gearbif"))
            .args([
                "synth",
                "--effect",
                "none",
                "--ringdowns",
                "2",
                "--driven",
                "1",
            ])
            .args(["--turns", "10", "--seed", seed, "--out"])
            .arg(&p)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        p.display().to_string()
    };
    let (a, b) = (set("a", "1"), set("b", "2"));
    killed_writer_leaves_one_whole_result(
        "diagnose",
        &["diagnose", &a, "--no-heldout"],
        &["diagnose", &b, "--no-heldout"],
    );
    std::fs::remove_dir_all(&root).ok();
}

/// `report` killed while it replaces the report of another gear.
#[test]
fn killed_report_leaves_one_whole_result() {
    killed_writer_leaves_one_whole_result(
        "report",
        &["report", "--quiet", "--eta", "20"],
        &["report", "--quiet"],
    );
}

/// The hidden temporaries (`.NAME.tmp-PID…`) anywhere under `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    let mut v = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().to_string();
            if name.starts_with('.') && name.contains(".tmp-") {
                v.push(e.path().display().to_string());
            }
            if e.path().is_dir() {
                v.extend(temporaries(&e.path()));
            }
        }
    }
    v
}

/// Runs `args` (writing into `root`) with the `n`-th output write failing with ENOSPC, for n = 1,
/// 2, … until a run writes everything; `check` inspects `root` after each failed run. Returns
/// the number of failed runs (each must exit with 2 naming the full disk).
fn fail_each_write(root: &Path, args: &[&str], check: impl Fn(usize)) -> usize {
    for n in 1..100 {
        let o = Command::new(env!("CARGO_BIN_EXE_gearbif"))
            .args(args)
            .current_dir(root)
            .env("GEARBIF_FAIL_WRITE", n.to_string())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        if o.status.success() {
            return n - 1;
        }
        assert_eq!(o.status.code(), Some(2), "write {n} of {args:?}: {err}");
        assert!(
            err.contains("No space left"),
            "write {n} of {args:?}: {err}"
        );
        check(n);
    }
    panic!("{args:?} never finished");
}

/// A full disk in the middle of the output (every write failing in turn, through the same
/// error path a real ENOSPC takes) leaves no temporary and no partial result: a staged folder
/// (`synth`), staged flag files (`simulate --out --events`) and a figure's staged files (`figure
/// fig5`, six files) stay as the earlier result; a
/// sweep's work folder holds no completion marker until its last write, and a rerun completes it
/// with the files of an uninterrupted run.
#[test]
fn a_full_disk_mid_output_leaves_no_temporary_and_no_partial_result() {
    let root = tmpdir("full-disk");
    let synth = |seed: &'static str| {
        vec![
            "synth",
            "--effect",
            "none",
            "--out",
            "set",
            "--ringdowns",
            "2",
            "--driven",
            "1",
            "--turns",
            "5",
            "--truth",
            "--seed",
            seed,
        ]
    };
    let sim = |f: &'static str| {
        vec![
            "simulate",
            "--f",
            f,
            "--periods",
            "2",
            "--out",
            "sub/x.csv",
            "--events",
            "sub/e.csv",
        ]
    };
    let fig =
        |zeta: &'static str| vec!["figure", "fig5", "--quiet", "--zeta", zeta, "--out", "figs"];
    for args in [synth("1"), sim("1"), fig("1.0")] {
        let o = Command::new(env!("CARGO_BIN_EXE_gearbif"))
            .args(&args)
            .current_dir(&root)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    for args in [synth("2"), sim("1.5"), fig("1.3")] {
        let before = files(&root, false);
        let failed = fail_each_write(&root, &args, |n| {
            assert!(
                files(&root, false) == before,
                "write {n} of {args:?} changed the folder: {:?}",
                files(&root, false).keys().collect::<Vec<_>>()
            );
        });
        assert!(failed >= 2, "{args:?}: {failed} writes");
    }
    // a new folder under a missing parent: nothing of it is left either
    let fresh = [
        "simulate",
        "--f",
        "1",
        "--periods",
        "2",
        "--out",
        "new/x.csv",
    ];
    let failed = fail_each_write(&root, &fresh, |_| assert!(!root.join("new").exists()));
    assert_eq!(failed, 1);

    let small: Vec<&str> = SWEEP
        .iter()
        .map(|&a| match a {
            "theta:0:45:5" => "theta:0:10:5",
            "400" => "100",
            a => a,
        })
        .collect();
    let sweep_args: Vec<&str> = small.iter().copied().chain(["--out", "sweep"]).collect();
    let sweep_dir = root.join("sweep");
    let failed = fail_each_write(&root, &sweep_args, |n| {
        assert!(!sweep_dir.join("complete.json").exists(), "write {n}");
        assert!(
            temporaries(&root).is_empty(),
            "write {n}: {:?}",
            temporaries(&root)
        );
    });
    // each rerun resumes from the rows checkpointed before (the failing write counts from there)
    assert!(failed >= 4, "{failed} writes");
    let whole = root.join("sweep-whole");
    let o = Command::new(env!("CARGO_BIN_EXE_gearbif"))
        .args(&small)
        .arg("--out")
        .arg(&whole)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    same_files(&sweep_dir, &whole);
    assert!(temporaries(&root).is_empty(), "{:?}", temporaries(&root));
    std::fs::remove_dir_all(root).ok();
}

/// `figure fig5` killed at random moments while it rewrites its files in a folder that also holds
/// another figure (a run of a fraction of a second): after every kill the other figure is
/// untouched, each fig5 file is whole (the earlier version or the new one) and nothing but the
/// hidden staging folder of the killed run is added; the next complete run removes it.
#[test]
fn killed_figure_leaves_whole_files_and_the_other_figures() {
    let root = tmpdir("figure");
    let (out, b) = (root.join("out"), root.join("b"));
    run_ok(&["figure", "fig5", "--quiet", "--zeta", "1.0"], &out);
    std::fs::write(out.join("fig6.svg"), "another figure").unwrap();
    let earlier = files(&out, false);
    let args_b = ["figure", "fig5", "--quiet", "--zeta", "1.3"];
    let t = Instant::now();
    run_ok(&args_b, &b);
    let t_b = t.elapsed();
    let new = files(&b, false);
    assert!(
        new.iter().all(|(k, v)| earlier.get(k) != Some(v)),
        "the results must differ"
    );
    let mut rng = Rng(env_or("GEARBIF_KILL_SEED", 0x5eed_u64) | 1);
    for _ in 0..env_or("GEARBIF_KILLS", 6) {
        let mut child = gearbif(&args_b, &out).spawn().unwrap();
        std::thread::sleep(t_b.mul_f64(0.2 + 1.0 * rng.uniform()));
        let _ = child.kill();
        child.wait().unwrap();
        for (k, v) in files(&out, false) {
            if k.starts_with(".figure-fig5.tmp-") {
                continue;
            }
            assert!(
                earlier.get(&k) == Some(&v) || new.get(&k) == Some(&v),
                "after a kill {k} is neither version"
            );
        }
        assert_eq!(
            std::fs::read(out.join("fig6.svg")).unwrap(),
            b"another figure"
        );
    }
    run_ok(&args_b, &out);
    let mut want = new.clone();
    want.insert("fig6.svg".into(), b"another figure".to_vec());
    assert!(
        files(&out, false) == want,
        "the complete run differs or left temporaries"
    );
    std::fs::remove_dir_all(&root).ok();
}
