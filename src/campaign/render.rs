//! campaign.md: the campaign's tables (false positives, power per effect, confusion matrix, σ
//! coverage) in Markdown.

use super::cases::EFFECTS;
use super::metrics::Rate;
use super::runner::CampaignDoc;

fn pct(r: &Rate) -> String {
    match r.rate {
        Some(x) => format!(
            "{}/{} = {:.0} % [{:.0}, {:.0}]",
            r.k,
            r.n,
            100.0 * x,
            100.0 * r.lo95,
            100.0 * r.hi95
        ),
        None => "–".into(),
    }
}

fn num(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if x.abs() >= 0.01 && x.abs() < 1000.0 {
        format!("{:.3}", x)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    } else {
        format!("{x:.2e}")
    }
}

/// Renders the tables of a campaign.
pub fn markdown(doc: &CampaignDoc) -> String {
    let s = &doc.summary;
    let sp = &doc.spec;
    let mut o = format!(
        "# Campaign\n\nSchema `{}`. Sets: `{}` ({} ring-downs of {} s at {} frames/s, {} driven \
         runs of {} turns at {} samples/turn, {}–{} Hz); {} seeds per effect and size, {} per control; levels {}; generator RK4 step \
         {} s. Rates are k/n with the 95 % Clopper–Pearson interval in brackets.\n\n",
        doc.schema,
        sp.set.name,
        sp.set.ringdowns,
        sp.set.ringdown_s,
        sp.set.fps,
        sp.set.driven,
        sp.set.turns,
        sp.set.samples_per_turn,
        sp.set.f_min,
        sp.set.f_max,
        sp.seeds.len(),
        sp.null_seeds.len(),
        sp.levels
            .iter()
            .map(|l| num(*l))
            .collect::<Vec<_>>()
            .join(", "),
        sp.rk4_step_s
    );
    o.push_str("## False positives (controls: any verdict other than `none`)\n\n");
    o.push_str("| control | false-positive rate |\n|---|---|\n");
    for (k, r) in &s.false_positive_per_control {
        o.push_str(&format!("| `{k}` | {} |\n", pct(r)));
    }
    o.push_str(&format!(
        "| **pooled** (goal ≤ 5 %) | **{}** |\n\n",
        pct(&s.false_positive)
    ));
    o.push_str("## Detection power (named right, by size)\n\n");
    o.push_str("| effect | expected | size: named right | size at 90 % |\n|---|---|---|---|\n");
    for p in &s.power {
        let pts: Vec<String> = p
            .points
            .iter()
            .map(|q| format!("{}: {}/{}", num(q.size), q.named_right.k, q.named_right.n))
            .collect();
        let unit = if p.unit.is_empty() {
            String::new()
        } else {
            format!(" ({})", p.unit)
        };
        o.push_str(&format!(
            "| `{}`{unit} | `{}` | {} | {} |\n",
            p.effect,
            p.expected,
            pts.join("; "),
            p.size_90.map(num).unwrap_or_else(|| "not reached".into())
        ));
    }
    o.push_str(&format!(
        "\n## Honest verdicts\n\nA confident wrong name is a verdict that names a catalog effect \
         the truth does not contain (`partly_explained` and `unexplained` say that a significant \
         mismatch is left). Confident wrong names, over every case with an effect: {}. Honest \
         verdicts on the effects whose form the catalog does not contain (goal ≥ 90 %): {}.\n",
        pct(&s.confident_wrong),
        pct(&s.out_of_catalog_honest)
    ));
    o.push_str(&format!(
        "\n## The curve of what remains\n\nCurves whose ±2σ band holds the true curve of their \
         kind on at least 90 % of their grid (cases whose truth has one): {}. Controls \
         with a curve that stands: {}.\n",
        pct(&s.curve_coverage),
        pct(&s.curve_false_positive)
    ));
    o.push_str("\n## Confusion matrix (rows: truth, columns: verdict)\n\n| truth \\ verdict |");
    for c in &s.confusion.cols {
        o.push_str(&format!(" `{c}` |"));
    }
    o.push_str("\n|---|");
    o.push_str(&"---|".repeat(s.confusion.cols.len()));
    o.push('\n');
    for (i, r) in s.confusion.rows.iter().enumerate() {
        o.push_str(&format!("| `{r}` |"));
        for c in &s.confusion.counts[i] {
            o.push_str(&format!(" {c} |"));
        }
        o.push('\n');
    }
    o.push_str("\n## σ coverage (truth within ±2σ of the reported headline size)\n\n");
    o.push_str("| effect | within ±2σ |\n|---|---|\n");
    for (k, r) in &s.coverage.per_effect {
        o.push_str(&format!("| `{k}` | {} |\n", pct(r)));
    }
    o.push_str(&format!(
        "| **pooled** (goal ≥ 90 %) | **{}** |\n\nDetections without a reported size: {}; in \
         another unit: {}. Diagnoses that failed with an error: {}. Median time per diagnosis: \
         {:.1} s.\n",
        pct(&s.coverage.pooled),
        s.coverage.missing_size,
        s.coverage.other_unit,
        s.errors,
        s.median_seconds
    ));
    o.push_str("\n## The generator's forms\n\n| effect | form |\n|---|---|\n");
    for e in EFFECTS
        .iter()
        .filter(|e| sp.effects.iter().any(|x| x == e.id))
    {
        o.push_str(&format!("| `{}` | {} |\n", e.id, e.form));
    }
    o
}
