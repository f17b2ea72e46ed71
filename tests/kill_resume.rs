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
    for f in ["points.csv", "sweep.json", "rms_map.svg"] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(x == y, "{f} differs from the uninterrupted run");
    }
}

#[test]
fn killed_and_resumed_sweep_is_bit_identical() {
    let root = tmpdir("sweep");
    let (reference, killed) = (root.join("reference"), root.join("killed"));
    let t = Instant::now();
    run_to_end(&reference);
    let t_ref = t.elapsed();
    let seed = std::env::var("GEARBIF_KILL_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x5eed_u64);
    let kills: usize = std::env::var("GEARBIF_KILLS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(15);
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
