//! `--model FILE` as a process: the recorded gear of a model file with only the base terms gives
//! the paper's gear's answers; a model next to gear flags, and a malformed model file, exit 2 with
//! the file and the field named.
#![cfg(feature = "cli")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn gearbif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gearbif"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is JSON")
}

/// The lock-loss fold of the paper's gear, located on the gear and on its model file: the same
/// frequency (f_c = (g − η)/(2πζ) = 39.8396704 Hz) to 1e-9 Hz.
#[test]
fn locate_on_the_papers_model_file_is_the_papers_fold() {
    let model = asset("paper_gear.model.json");
    let common = [
        "locate",
        "--f",
        "39.7",
        "--kind",
        "fold",
        "--state-rad",
        "1.5808,250.3",
        "--json",
    ];
    let a = json(&gearbif(&common));
    let mut with_model = common.to_vec();
    with_model.extend(["--model", model.to_str().unwrap()]);
    let b = json(&gearbif(&with_model));
    let (fa, fb) = (
        a["point"]["free"].as_f64().unwrap(),
        b["point"]["free"].as_f64().unwrap(),
    );
    let fc = (298.452035046191 - 23.1) / (std::f64::consts::TAU * 1.1);
    assert!((fa - fc).abs() < 1e-8, "{fa} {fc}");
    assert!((fb - fa).abs() < 1e-9, "{fb} {fa}");
}

/// simulate --model on the base-only file ends where the paper's gear ends.
#[test]
fn simulate_on_the_papers_model_file_follows_the_papers_gear() {
    let model = asset("paper_gear.model.json");
    let common = ["simulate", "--f", "2.7", "--periods", "4", "--json"];
    let a = json(&gearbif(&common));
    let mut with_model = common.to_vec();
    with_model.extend(["--model", model.to_str().unwrap()]);
    let b = json(&gearbif(&with_model));
    for i in 0..2 {
        let (u, v) = (
            a["x_end"][i].as_f64().unwrap(),
            b["x_end"][i].as_f64().unwrap(),
        );
        assert!((u - v).abs() < 1e-7 * (1.0 + u.abs()), "{u} {v}");
    }
    assert_eq!(b["model"].as_str().unwrap(), model.to_str().unwrap());
}

/// map --model on the base-only file: the same image, Jacobians and multipliers (columns by name).
#[test]
fn map_on_the_papers_model_file_is_the_papers_map() {
    let model = asset("paper_gear.model.json");
    let common = [
        "map",
        "--f",
        "3",
        "--x0-deg",
        "170,18.85",
        "--section",
        "half",
        "--json",
    ];
    let a = json(&gearbif(&common));
    let mut with_model = common.to_vec();
    with_model.extend(["--model", model.to_str().unwrap()]);
    let b = json(&gearbif(&with_model));
    let close = |u: f64, v: f64| assert!((u - v).abs() < 1e-8 * (1.0 + u.abs()), "{u} {v}");
    for i in 0..2 {
        close(
            a["image"][i].as_f64().unwrap(),
            b["image"][i].as_f64().unwrap(),
        );
        close(
            a["multipliers"][i]["abs"].as_f64().unwrap(),
            b["multipliers"][i]["abs"].as_f64().unwrap(),
        );
    }
    let names = |v: &serde_json::Value| -> Vec<String> {
        v["param_names"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap().to_string())
            .collect()
    };
    let (na, nb) = (names(&a), names(&b));
    for (ka, n) in na.iter().enumerate() {
        let kb = nb.iter().position(|m| m == n).unwrap();
        for row in 0..2 {
            close(
                a["jac_p"][row][ka].as_f64().unwrap(),
                b["jac_p"][row][kb].as_f64().unwrap(),
            );
        }
    }
}

/// classify --model: the paper's model file classifies as the paper's gear; a static torque
/// makes the locked response T-periodic instead of T/2-periodic.
#[test]
fn classify_on_model_files() {
    let common = ["classify", "--f", "3", "--json"];
    let run = |file: Option<&str>| {
        let mut args = common.to_vec();
        let path = file.map(|f| asset(f).to_str().unwrap().to_string());
        if let Some(p) = &path {
            args.extend(["--model", p.as_str()]);
        }
        json(&gearbif(&args))["event_driven"]["rigorous"].clone()
    };
    let (a, b) = (run(None), run(Some("paper_gear.model.json")));
    assert_eq!(a["label"], b["label"]);
    let lyap = |v: &serde_json::Value| v["lyapunov"]["per_period"].as_f64().unwrap();
    let (la, lb) = (lyap(&a), lyap(&b));
    assert!((la - lb).abs() < 1e-6, "{la} {lb}");
    let c = run(Some("static_torque.model.json"));
    assert_eq!(a["label"], "T/2");
    assert_eq!(c["label"], "T");
}

/// Gear flags next to --model, and malformed files: exit 2, the option or the file and field named.
#[test]
fn conflicts_and_bad_model_files_exit_2() {
    let model = asset("paper_gear.model.json");
    let m = model.to_str().unwrap();
    let out = gearbif(&["simulate", "--model", m, "--theta-deg", "10"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--model") && err.contains("--theta-deg"),
        "{err}"
    );

    let dir = std::env::temp_dir().join(format!("gearbif-recorded-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(&model).unwrap();
    let cases = [
        (
            text.replace("\"name\": \"eta\"", "\"name\": \"etta\""),
            "(etta)",
        ),
        (text.replace("gearbif.model/1", "gearbif.model/9"), "schema"),
        (
            text.replace("[\n        4.0,", "[\n        -4.0,"),
            "covariance",
        ),
    ];
    for (k, (bad, field)) in cases.iter().enumerate() {
        assert_ne!(bad, &text, "case {k} edits the file");
        let p = dir.join(format!("bad{k}.json"));
        std::fs::write(&p, bad).unwrap();
        let out = gearbif(&["simulate", "--model", p.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "case {k}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(p.to_str().unwrap()) && err.contains(field),
            "{field}: {err}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
