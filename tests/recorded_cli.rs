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

/// The paper's model file with the covariance over (g, ζ, η) replaced by `cov` (row by row),
/// written to a fresh file.
fn with_covariance(tag: &str, cov: [[f64; 3]; 3]) -> PathBuf {
    let text = std::fs::read_to_string(asset("paper_gear.model.json")).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    doc["covariance"] = serde_json::json!({ "names": ["g", "zeta", "eta"], "matrix": cov });
    let p = std::env::temp_dir().join(format!("gearbif-sigma-{tag}-{}.json", std::process::id()));
    std::fs::write(&p, serde_json::to_string(&doc).unwrap()).unwrap();
    p
}

/// The paper's gear: f_c = (g − η)/(2πζ) (model.md).
const G: f64 = 298.452035046191;
fn f_c(eta: f64) -> f64 {
    (G - eta) / (std::f64::consts::TAU * 1.1)
}

/// σ of the lock-loss fold from the model file's covariance: locate --model gives the closed
/// form's σ² = aᵀCa with a = ∂f_c/∂(g, ζ, η) = (1, −2π f_c, −1)/(2πζ), to 1e-5 relative; and
/// boundary --model along η gives, at every point, the σ of (g, ζ) alone (η is the coordinate).
#[test]
fn sigma_of_located_points_is_the_closed_forms() {
    let cov = [[4.0, 0.0, 1.0], [0.0, 4e-4, 0.0], [1.0, 0.0, 1.0]];
    let file = with_covariance("fold", cov);
    let m = file.to_str().unwrap();
    let a = |eta: f64| {
        let s = std::f64::consts::TAU * 1.1;
        [1.0 / s, -f_c(eta) / 1.1, -1.0 / s]
    };
    let quad = |g: [f64; 3], keep: &[usize]| {
        let mut q = 0.0;
        for &i in keep {
            for &j in keep {
                q += g[i] * cov[i][j] * g[j];
            }
        }
        q.sqrt()
    };
    let out = json(&gearbif(&[
        "locate",
        "--model",
        m,
        "--f",
        "39.7",
        "--kind",
        "fold",
        "--state-rad",
        "1.5808,250.3",
        "--json",
    ]));
    let sigma = out["sigma"]["sigma"].as_f64().unwrap();
    let want = quad(a(23.1), &[0, 1, 2]);
    assert!(
        (sigma / want - 1.0).abs() < 1e-5,
        "σ {sigma}, closed form {want}"
    );

    let out = json(&gearbif(&[
        "boundary",
        "--model",
        m,
        "--free",
        "f",
        "--along",
        "eta",
        "--range",
        "23.1:24.1",
        "--step",
        "0.5",
        "--start-free",
        "39.8",
        "--start-state-rad",
        "1.5808,250.3",
        "--method",
        "natural",
        "--json",
    ]));
    let points = out["curves"][0][1]["points"].as_array().unwrap();
    let sigmas = out["sigma"].as_array().unwrap();
    assert_eq!(points.len(), 3);
    assert_eq!(sigmas.len(), 3);
    for (p, s) in points.iter().zip(sigmas) {
        let eta = p["along"].as_f64().unwrap();
        let f = p["free"].as_f64().unwrap();
        assert!((f - f_c(eta)).abs() < 1e-8, "{f} {}", f_c(eta));
        let (got, want) = (s["sigma"].as_f64().unwrap(), quad(a(eta), &[0, 1]));
        assert!(
            (got / want - 1.0).abs() < 1e-5,
            "at η = {eta}: σ {got}, {want}"
        );
        assert_eq!(s["omitted"], serde_json::json!(["eta"]));
    }
    std::fs::remove_file(&file).ok();
}

/// continue --model on the paper's model file follows the paper's branch: in η at 3 Hz, the same
/// points as without --model; the stop reason in words.
#[test]
fn continue_on_the_papers_model_file_is_the_papers_branch() {
    let model = asset("paper_gear.model.json");
    let common = [
        "continue",
        "--f",
        "3",
        "--param",
        "eta",
        "--range",
        "20:26",
        "--max-steps",
        "12",
        "--json",
    ];
    let a = json(&gearbif(&common));
    let mut with_model = common.to_vec();
    with_model.extend(["--model", model.to_str().unwrap()]);
    let b = json(&gearbif(&with_model));
    let (pa, pb) = (
        a["branches"][0]["points"].as_array().unwrap(),
        b["branches"][0]["points"].as_array().unwrap(),
    );
    assert_eq!(pa.len(), pb.len());
    for (u, v) in pa.iter().zip(pb) {
        let (x, y) = (u["param"].as_f64().unwrap(), v["param"].as_f64().unwrap());
        assert!((x - y).abs() < 1e-8 * (1.0 + x.abs()), "{x} {y}");
        for i in 0..2 {
            let (x, y) = (u["x"][i].as_f64().unwrap(), v["x"][i].as_f64().unwrap());
            assert!((x - y).abs() < 1e-8 * (1.0 + x.abs()), "{x} {y}");
        }
    }
    let mut text = with_model.clone();
    text.retain(|&s| s != "--json");
    let out = gearbif(&text);
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(
        s.contains("stop: took the largest number of steps, 12"),
        "{s}"
    );
}

/// diagram --model runs on the recorded gear (seeds from simulations), each run ends at a bound
/// of the range; every command refuses the gear flags next to --model, naming the flag.
#[test]
fn diagram_on_a_model_file_and_conflicting_flags() {
    let model = asset("static_torque.model.json");
    let m = model.to_str().unwrap();
    let d = json(&gearbif(&[
        "diagram",
        "--model",
        m,
        "--param",
        "f",
        "--range",
        "2.6:2.8",
        "--grid",
        "2",
        "--max-steps",
        "40",
        "--relax",
        "50",
        "--json",
    ]));
    let runs = d["branches"].as_array().unwrap();
    assert!(!runs.is_empty());
    for r in runs {
        assert_eq!(r["branch"]["stop"]["reason"], "parameter_bound", "{r}");
    }
    for (args, flag) in [
        (
            &["continue", "--zeta", "1", "--f", "3", "--range", "1:2"][..],
            "--zeta",
        ),
        (&["diagram", "--eta", "20", "--range", "1:2"][..], "--eta"),
        (&["boundary", "--theta-deg", "10"][..], "--theta-deg"),
    ] {
        let cmd = args[0];
        let mut a = args.to_vec();
        a.extend(["--model", m]);
        let out = gearbif(&a);
        assert_eq!(out.status.code(), Some(2), "{cmd}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("--model") && err.contains(flag),
            "{cmd}: {err}"
        );
    }
}

/// The paper's model file with a quadratic drag q (|β̇|/4)² (effect `quadratic_drag`), a
/// covariance over (g, ζ, η, q) and the recorded drive frequencies 1–2.5 Hz.
fn with_drag(q: f64, cov: &[[f64; 4]; 4], drive_hz: [f64; 2]) -> PathBuf {
    let text = std::fs::read_to_string(asset("paper_gear.model.json")).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    for p in doc["parameters"].as_array_mut().unwrap() {
        if p["name"] == "drag_q" {
            p["value"] = serde_json::json!(q);
        }
    }
    doc["effects"] = serde_json::json!(["quadratic_drag"]);
    doc["covariance"] =
        serde_json::json!({ "names": ["g", "zeta", "eta", "drag_q"], "matrix": cov });
    doc["recorded"] = serde_json::json!({ "drive_hz": drive_hz });
    let p = std::env::temp_dir().join(format!(
        "gearbif-drag-{}-{}.json",
        drive_hz[1],
        std::process::id()
    ));
    std::fs::write(&p, serde_json::to_string(&doc).unwrap()).unwrap();
    p
}

/// report --model on a gear with a quadratic drag at Θ = 0, against the closed form: the locked
/// orbit turns uniformly, so its fold is where the coupling's largest torque g meets the braking,
/// h(f) = 2πζ f + η + q (2πf/4)² − g = 0. f_c, its shift by the drag Δ = f_c(q) − f_c(0) and the
/// σ of Δ from the gradient of the difference, d = ∇f_c(q) − ∇f_c(0) (∇f_c = (1, −2πf, −1,
/// −(2πf/4)²)/h′(f) over (g, ζ, η, q), the last entry 0 without the drag) are the report's to
/// 1e-7 Hz and 1e-4 relative; f_c far above the recorded 1–2.5 Hz is said to extrapolate the
/// drag law. The recorded range and conflicting flags of sweep, report and figure exit 2.
#[test]
fn report_on_a_model_file_is_the_closed_forms_effect_table() {
    let (g, zeta, eta, q) = (G, 1.1, 23.1, 0.01);
    let cov = [
        [4.0, 0.0, 1.0, 0.0],
        [0.0, 4e-4, 0.0, 0.0],
        [1.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1e-6],
    ];
    let file = with_drag(q, &cov, [1.0, 2.5]);
    let m = file.to_str().unwrap();
    let out = std::env::temp_dir().join(format!("gearbif-report-model-{}", std::process::id()));
    let run = gearbif(&[
        "report",
        "--model",
        m,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let section = |id: &str| {
        doc["sections"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["id"] == id)
            .unwrap()["data"]
            .clone()
    };
    let tau = std::f64::consts::TAU;
    let a = q * (tau / 4.0).powi(2);
    let fq = (-tau * zeta + ((tau * zeta).powi(2) - 4.0 * a * (eta - g)).sqrt()) / (2.0 * a);
    let f0 = (g - eta) / (tau * zeta);
    let grad = |f: f64, q: f64| {
        let h1 = tau * zeta + 2.0 * q * (tau / 4.0).powi(2) * f;
        [
            1.0,
            -tau * f,
            -1.0,
            -(tau * f / 4.0).powi(2) * (q != 0.0) as u8 as f64,
        ]
        .map(|v| v / h1)
    };
    let (gq, g0) = (grad(fq, q), grad(f0, 0.0));
    let d: Vec<f64> = (0..4).map(|i| gq[i] - g0[i]).collect();
    let var: f64 = (0..4)
        .flat_map(|i| (0..4).map(move |j| (i, j)))
        .map(|(i, j)| d[i] * cov[i][j] * d[j])
        .sum();
    let limits = section("limits");
    let fc = limits
        .as_array()
        .unwrap()
        .iter()
        .find(|l| l["name"] == "f_c")
        .expect("the lock loss is located");
    assert!(
        (fc["f_hz"].as_f64().unwrap() - fq).abs() < 1e-7,
        "{fc} {fq}"
    );
    let shifts = section("effects");
    let row = &shifts[0];
    assert_eq!(row["off"], serde_json::json!(["quadratic_drag"]));
    assert!(
        (row["without_hz"].as_f64().unwrap() - f0).abs() < 1e-7,
        "{row}"
    );
    assert!(
        (row["delta_hz"].as_f64().unwrap() - (fq - f0)).abs() < 1e-7,
        "{row}"
    );
    let s = row["sigma_hz"].as_f64().unwrap();
    assert!(
        (s / var.sqrt() - 1.0).abs() < 1e-4,
        "σ {s}, closed form {}",
        var.sqrt()
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("lies outside the recorded 1.00–2.50 Hz: an extrapolation of the drag law"),
        "{md}"
    );
    // locate and boundary say so too, in f (not in η), and not inside the recorded range
    let loc = |file: &str, f: &str| {
        json(&gearbif(&[
            "locate",
            "--model",
            file,
            "--f",
            f,
            "--kind",
            "fold",
            "--section",
            "strob",
            "--state-rad",
            "1.5708,222",
            "--json",
        ]))
    };
    let out_of = |v: &serde_json::Value| v["outside_recorded"].to_string();
    assert!(out_of(&loc(m, "35")).contains(
        "f = 35.4 Hz lies outside the recorded 1.00–2.50 Hz: an extrapolation of the drag law"
    ));
    let curve = json(&gearbif(&[
        "boundary",
        "--model",
        m,
        "--free",
        "f",
        "--along",
        "eta",
        "--range",
        "23.1:23.6",
        "--step",
        "0.5",
        "--start-free",
        "35",
        "--start-state-rad",
        "1.5708,222",
        "--section",
        "strob",
        "--method",
        "natural",
        "--json",
    ]));
    assert!(
        out_of(&curve).contains("(2 of 2 points of the curve lie that far out)"),
        "{curve}"
    );
    let near = with_drag(q, &cov, [20.0, 30.0]);
    assert!(loc(near.to_str().unwrap(), "35")["outside_recorded"].is_null());
    std::fs::remove_file(&near).ok();
    // the conflicting flags: exit 2, the flag and the file's option named
    for args in [
        vec!["report", "--model", m, "--zeta", "2"],
        vec!["sweep", "--model", m, "--theta-deg", "3"],
        vec!["figure", "orbit", "--model", m, "--eta", "3"],
        vec!["figure", "fig5", "--model", m],
        vec![
            "sweep",
            "--model",
            m,
            "--rows",
            "theta:0:10:10",
            "--cols",
            "f:1:2:1",
        ],
    ] {
        let o = gearbif(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("--model"), "{args:?}: {err}");
    }
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_file(&file).ok();
}

/// The column `name` of a CSV text (lines starting with `#` skipped).
fn column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = head.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
        .collect()
}

/// sweep --model on the paper's model file, a tiny grid in (η, f) at Θ = 0: the same mean lag
/// δ_avg and Lyapunov exponent at every point as the paper's gear's own sweep; figure --model
/// writes its files.
#[test]
fn sweep_and_figure_on_a_model_file() {
    let m = asset("paper_gear.model.json");
    let m = m.to_str().unwrap();
    let out = std::env::temp_dir().join(format!("gearbif-sweep-model-{}", std::process::id()));
    let grid = [
        "--rows",
        "eta:20:25:5",
        "--cols",
        "f:1:2:1",
        "--settle",
        "100",
        "--record",
        "4",
        "--analysis",
        "6",
        "--quiet",
        "--out",
    ];
    let (a, b) = (out.join("model"), out.join("gear"));
    let mut args = vec!["sweep", "--model", m];
    args.extend(grid);
    args.push(a.to_str().unwrap());
    let run = gearbif(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let mut args = vec!["sweep", "--theta-deg", "0"];
    args.extend(grid);
    args.push(b.to_str().unwrap());
    assert!(gearbif(&args).status.success());
    let (ca, cb) = (
        std::fs::read_to_string(a.join("points.csv")).unwrap(),
        std::fs::read_to_string(b.join("points.csv")).unwrap(),
    );
    assert!(ca.starts_with("row,col,eta,f,"), "{ca}");
    for (x, y) in [
        ("delta_avg_deg", "delta_avg_deg"),
        ("lyapunov_per_period", "lyapunov"),
    ] {
        let (u, v) = (column(&ca, x), column(&cb, y));
        assert_eq!(u.len(), 4);
        assert_eq!(u.len(), v.len());
        for (p, q) in u.iter().zip(&v) {
            assert!((p - q).abs() < 1e-6, "{x}: {p} {q}");
        }
    }
    let fig = out.join("fig");
    let run = gearbif(&[
        "figure",
        "lyapunov",
        "--model",
        m,
        "--f-range",
        "1:2",
        "--points",
        "2",
        "--out",
        fig.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(fig.join("lyapunov.svg").is_file());
    std::fs::remove_dir_all(&out).ok();
}
