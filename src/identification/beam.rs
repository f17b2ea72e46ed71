//! The selection over rounds ([`super::select`]'s rounds) as a beam of at most two branches.
//!
//! Each round accepts the best significant candidate of the current model. When a named rival of
//! another effect is not significantly worse than it ([`close_rival`]), the greedy choice between
//! them would rest on a difference the data do not support, and what later rounds add rests on
//! that choice. The selection then forks: each of the two is accepted in a branch of its own and
//! the rounds go on in both, in step. After each later round a branch whose model predicts the
//! held-out windows significantly worse than the other's (the paired z of [`compare`] at the fork
//! round's threshold) is left; when both run to their end, the one whose final model predicts
//! the held-out windows better is kept. At most two branches: a fork only where one branch is
//! left (before any fork, or after the other was left).

use super::judge::{compare, Comparison};
use super::select::{
    accept, choose_members, choose_named, close_rival, judge_round, ModelState, SelectCtx, Tried,
};
use crate::progress::{stage, Observer};

/// A round whose accepted candidate and a named rival could not be told apart, and how the
/// branch of each ended ([`select`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Fork {
    /// The round.
    pub round: usize,
    /// The effect accepted in that round on the kept branch.
    pub kept: String,
    /// The effect accepted in that round on the other branch.
    pub other: String,
    /// Held-out z of the larger-gain candidate of the two against the other in their round
    /// (below the round's threshold: no significant difference).
    pub round_z: f64,
    /// Effects of the kept branch's model when the fork was decided (its final model when both
    /// branches ran to their end).
    pub kept_effects: Vec<String>,
    /// Effects of the other branch's model then.
    pub other_effects: Vec<String>,
    /// Held-out χ² gain of the kept branch's model over the other's then (≥ 0).
    pub final_gain: f64,
    /// Its z (paired windows).
    pub final_z: f64,
    /// The round after which the other branch was left for predicting significantly worse
    /// (`None`: both ran to their end).
    pub pruned_after: Option<usize>,
}

impl Fork {
    /// "branch of `kept` (its effects) was kept over that of `other` (its effects)": the fork's
    /// outcome in words, for the progress line and report.md (each puts its own article).
    pub fn outcome(&self) -> String {
        format!(
            "branch of `{}` ({}) was kept over that of `{}` ({})",
            self.kept,
            self.kept_effects.join(" + "),
            self.other,
            self.other_effects.join(" + ")
        )
    }
}

/// The selection's result: every candidate tried on the kept branch (the accepted ones with
/// their refitted state), its final model, and the forks taken on the way to it.
#[derive(Debug, Clone)]
pub struct Selection {
    /// Candidates of all rounds.
    pub tried: Vec<Tried>,
    /// The final model.
    pub fin: ModelState,
    /// Forks.
    pub forks: Vec<Fork>,
}

/// A branch of the selection.
struct Branch {
    tried: Vec<Tried>,
    cur: ModelState,
    /// The effect this branch accepted at the fork (empty before it).
    label: String,
    /// No candidate was accepted in its last round.
    ended: bool,
}

/// Where the selection forked.
struct ForkAt {
    round: usize,
    z: f64,
    z_crit: f64,
}

/// A branch left for predicting significantly worse than the other.
struct Pruned {
    branch: Branch,
    cmp: Comparison,
}

/// The selection from `base` (see the module); `progress` gets a line per candidate.
pub fn select(ctx: &SelectCtx, base: ModelState, progress: &dyn Observer) -> Selection {
    let mut branches = vec![Branch {
        tried: Vec::new(),
        cur: base,
        label: String::new(),
        ended: false,
    }];
    let mut open: Option<ForkAt> = None;
    let mut forks = Vec::new();
    for round in 1..=ctx.max_rounds {
        let mut next = Vec::with_capacity(2);
        for b in branches {
            if b.ended {
                next.push(b);
            } else {
                next.extend(advance(ctx, b, round, &mut open, progress));
            }
        }
        branches = next;
        let done = round == ctx.max_rounds || branches.iter().all(|b| b.ended);
        if done {
            break;
        }
        // a fork still open after a later round: the branch significantly worse is left (at the
        // end, `finish` compares the final models)
        if let Some(at) = open.as_ref().filter(|f| f.round < round) {
            if let Some(p) = prune(ctx, &mut branches, at.z_crit, round, progress) {
                let kept = &mut branches[0];
                forks.push(record(at, kept, &p.branch, &p.cmp, Some(round)));
                kept.label.clear();
                open = None;
            }
        }
    }
    finish(ctx, branches, open, forks, progress)
}

/// One round of branch `b`: its candidates judged, then the best accepted (one branch), it and
/// its close rival accepted in a branch each (two; only while no fork is `open`, i.e. `b` is the
/// only branch), or nothing accepted (the branch ends).
fn advance(
    ctx: &SelectCtx,
    mut b: Branch,
    round: usize,
    at: &mut Option<ForkAt>,
    progress: &dyn Observer,
) -> Vec<Branch> {
    let label = if b.label.is_empty() {
        String::new()
    } else {
        format!(" (branch {})", b.label)
    };
    let Some(mut judged) = judge_round(ctx, &b.cur, round, &label, progress) else {
        b.ended = true;
        return vec![b];
    };
    let z_crit = judged[0].z_crit;
    let passed = choose_members(ctx, &mut judged, z_crit);
    let Some(bi) = choose_named(ctx, &judged, &passed, z_crit) else {
        for t in &mut judged {
            t.state = None;
        }
        b.tried.extend(judged);
        b.ended = true;
        return vec![b];
    };
    let rival = (ctx.fork_close_rivals && at.is_none())
        .then(|| close_rival(ctx, &judged, &passed, bi, z_crit))
        .flatten();
    let Some((ri, z)) = rival else {
        b.cur = accept(ctx, &mut judged, bi);
        b.tried.extend(judged);
        return vec![b];
    };
    let names = [bi, ri].map(|k| judged[k].candidate.effect.id.to_string());
    stage(
        progress,
        &format!(
            "round {round}: {} and {} not told apart (held-out z {z:.2} < {z_crit:.2}): a \
             branch for each",
            names[0], names[1]
        ),
    );
    *at = Some(ForkAt { round, z, z_crit });
    // only the two accepted keep their refitted states (`accept` drops the others' anyway)
    for (k, t) in judged.iter_mut().enumerate() {
        if k != bi && k != ri {
            t.state = None;
        }
    }
    [(bi, ri, 0), (ri, bi, 1)]
        .into_iter()
        .map(|(k, o, n)| {
            let mut r = judged.clone();
            r[o].forked = true;
            let cur = accept(ctx, &mut r, k);
            let mut tried = b.tried.clone();
            tried.extend(r);
            Branch {
                tried,
                cur,
                label: names[n].clone(),
                ended: false,
            }
        })
        .collect()
}

/// Of two branches, the one whose model predicts the held-out windows significantly worse than
/// the other's (paired z ≥ `z_crit`) is taken out and returned.
fn prune(
    ctx: &SelectCtx,
    branches: &mut Vec<Branch>,
    z_crit: f64,
    round: usize,
    progress: &dyn Observer,
) -> Option<Pruned> {
    if branches.len() != 2 {
        return None;
    }
    let c = compare(
        &branches[0].cur.held,
        &branches[1].cur.held,
        ctx.wins,
        ctx.runs,
    );
    let loser = if c.improves(z_crit) {
        0
    } else if c.worsens(z_crit) {
        1
    } else {
        return None;
    };
    let branch = branches.remove(loser);
    stage(
        progress,
        &format!(
            "after round {round}: the branch of {} predicts the held-out windows significantly \
             worse than that of {} (z {:.2} ≥ {z_crit:.2}) and is left",
            branch.label,
            branches[0].label,
            c.z.abs()
        ),
    );
    Some(Pruned { branch, cmp: c })
}

/// The kept branch's selection with the forks' records (`forks`, those decided by pruning): of
/// two branches left at the end (an `open` fork), the one whose final model predicts the
/// held-out windows better.
fn finish(
    ctx: &SelectCtx,
    mut branches: Vec<Branch>,
    open: Option<ForkAt>,
    mut forks: Vec<Fork>,
    progress: &dyn Observer,
) -> Selection {
    let kept = match (open, branches.len()) {
        (Some(at), 2) => {
            let b = branches.pop().expect("two branches");
            let a = branches.pop().expect("two branches");
            let c = compare(&a.cur.held, &b.cur.held, ctx.wins, ctx.runs);
            let (kept, other) = if c.gain > 0.0 { (b, a) } else { (a, b) };
            forks.push(record(&at, &kept, &other, &c, None));
            kept
        }
        _ => branches.pop().expect("a branch"),
    };
    // (a fork decided by pruning had its line then)
    for f in forks.iter().filter(|f| f.pruned_after.is_none()) {
        stage(
            progress,
            &format!(
                "round {}: the {}: held-out χ² gain {:.1}, z {:.2}",
                f.round,
                f.outcome(),
                f.final_gain,
                f.final_z,
            ),
        );
    }
    Selection {
        tried: kept.tried,
        fin: kept.cur,
        forks,
    }
}

/// The fork's record: `kept` over `other`, `c` their comparison (either way round).
fn record(
    at: &ForkAt,
    kept: &Branch,
    other: &Branch,
    c: &Comparison,
    pruned_after: Option<usize>,
) -> Fork {
    let effects = |b: &Branch| b.cur.effects.iter().map(|e| e.id.to_string()).collect();
    Fork {
        round: at.round,
        kept: kept.label.clone(),
        other: other.label.clone(),
        round_z: at.z,
        kept_effects: effects(kept),
        other_effects: effects(other),
        final_gain: c.gain.abs(),
        final_z: c.z.abs(),
        pruned_after,
    }
}
