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
//!
//! Before forking, the joint check ([`on_top_of_each_other`]): the members of each one's slot
//! are proposed on top of the model with the other, refitted and judged against it as any
//! candidate is against the current model, the member that would be accepted chosen as in a
//! round. When each is significant on top of the other, neither explains what the other does:
//! both are accepted in the round and the selection goes on without a fork, from the better of
//! the two models with both (each effect's member chosen on top of the other; [`Joint::order`]).
//! The order of their acceptance then decides nothing, and the rounds of two branches are not
//! spent. (Each branch's next round would judge the other effect the same way, at that round's
//! threshold, among all the candidates proposed there; a third effect that gains more there is
//! judged in the next round on top of both.) A joint needs room for two more effects
//! ([`SelectCtx::max_effects`]); without it the round forks.

use super::judge::{compare, Comparison};
use super::propose::Candidate;
use super::select::{
    accept, choose_members, choose_named, close_rival, converge, evaluate, judge_round,
    proposed_on, report_tried, tried, ModelState, SelectCtx, Tried,
};
use super::shooting::par_map;
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

/// A round whose accepted candidate and its close rival were each significant on top of the
/// other, and were both accepted in it ([`on_top_of_each_other`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Joint {
    /// The round.
    pub round: usize,
    /// The effect accepted on the round's model (its member as chosen in the round).
    pub first: String,
    /// Its close rival, accepted on top of it.
    pub second: String,
    /// The first's member (its terms), as chosen in the round.
    pub first_terms: Vec<String>,
    /// The second's member, as chosen on top of the first.
    pub second_terms: Vec<String>,
    /// Held-out z of the first against the second in the round (below the round's threshold).
    pub round_z: f64,
    /// The round's threshold.
    pub z_crit: f64,
    /// Held-out z and χ² gain of the second's chosen member refitted on top of the first,
    /// against the model with the first.
    pub second_on_first: (f64, f64),
    /// The same for the first's chosen member on top of the second.
    pub first_on_second: (f64, f64),
    /// Held-out χ² gain and z of the kept model (the second's member on top of the first) over
    /// the other order's (the first's member chosen on top of the second), both ≥ 0.
    pub order: (f64, f64),
}

/// The selection's result: every candidate tried on the kept branch (the accepted ones with
/// their refitted state), its final model, and how the close rivals on the way to it were
/// decided.
#[derive(Debug, Clone)]
pub struct Selection {
    /// Candidates of all rounds.
    pub tried: Vec<Tried>,
    /// The final model.
    pub fin: ModelState,
    /// How its close rivals were decided.
    pub rivals: Rivals,
}

/// How the close rivals of a selection were decided: forks, and rivals accepted together.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Rivals {
    /// Forks.
    pub forks: Vec<Fork>,
    /// Close rivals accepted together on the kept branch.
    pub joints: Vec<Joint>,
}

/// A branch of the selection.
struct Branch {
    tried: Vec<Tried>,
    cur: ModelState,
    /// The effect this branch accepted at the fork (empty before it).
    label: String,
    /// No candidate was accepted in its last round.
    ended: bool,
    /// Close rivals accepted together on this branch.
    joints: Vec<Joint>,
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
        joints: Vec::new(),
    }];
    let mut open: Option<ForkAt> = None;
    let mut forks = Vec::new();
    for round in 1..=ctx.max_effects {
        let mut next = Vec::with_capacity(2);
        for b in branches {
            if b.ended {
                next.push(b);
            } else {
                next.extend(advance(ctx, b, round, &mut open, progress));
            }
        }
        branches = next;
        let done = round == ctx.max_effects || branches.iter().all(|b| b.ended);
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
/// its close rival accepted together when each is significant on top of the other ([`joint`];
/// one branch), or else in a branch each (two; only while no fork is `open`, i.e. `b` is the
/// only branch), or nothing accepted (the branch ends, also when its model holds
/// [`SelectCtx::max_effects`] effects).
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
    if b.cur.effects.len() >= ctx.max_effects {
        b.ended = true;
        return vec![b];
    }
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
    // the two accepted refitted to convergence (in parallel); only they keep their states
    for (k, t) in judged.iter_mut().enumerate() {
        if k != bi && k != ri {
            t.state = None;
        }
    }
    let conv = par_map(2, |n| {
        let k = [bi, ri][n];
        converge(ctx, judged[k].state.as_ref().expect("evaluated"))
    });
    let [sa, sb]: [ModelState; 2] = conv.try_into().expect("two states");
    // the joint check, when the model has room for both
    let check = JointCheck {
        pair: (bi, ri),
        states: (&sa, &sb),
        round_z: z,
        round,
    };
    let room = b.cur.effects.len() + 2 <= ctx.max_effects;
    if let Some((on_top, j, below)) = room
        .then(|| joint(ctx, &judged, &check, &label, progress))
        .flatten()
    {
        let above = if below == bi { ri } else { bi };
        judged[below].accepted = true;
        judged[above].joined = true;
        judged[above].state = None;
        let k = on_top
            .iter()
            .position(|t| t.accepted)
            .expect("one accepted");
        b.cur = converge(ctx, on_top[k].state.as_ref().expect("evaluated"));
        b.tried.extend(judged);
        b.tried.extend(on_top);
        b.joints.push(j);
        return vec![b];
    }
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
    [(bi, ri, 0, sa), (ri, bi, 1, sb)]
        .into_iter()
        .map(|(k, o, n, cur)| {
            let mut r = judged.clone();
            r[o].forked = true;
            r[k].accepted = true;
            r[o].state = None;
            let mut tried = b.tried.clone();
            tried.extend(r);
            Branch {
                tried,
                cur,
                label: names[n].clone(),
                ended: false,
                joints: b.joints.clone(),
            }
        })
        .collect()
}

/// The two close rivals of a round and their models ([`joint`]).
struct JointCheck<'s> {
    /// Indices into the round: the accepted candidate, its rival.
    pair: (usize, usize),
    /// The round's model with each of them, refitted to convergence.
    states: (&'s ModelState, &'s ModelState),
    /// Held-out z of the first against the second.
    round_z: f64,
    /// The round.
    round: usize,
}

/// The members of one effect's slot judged on top of the model with another effect
/// ([`on_top_of_each_other`]).
#[derive(Debug, Clone)]
pub struct OnTop {
    /// The members the proposer offers there, each refitted and compared with that model
    /// (empty: it offers none).
    pub tried: Vec<Tried>,
    /// The member that would be accepted there: of the significant ones, after the choice
    /// between nested members ([`choose_members`]), the one of largest held-out gain; `None`
    /// when none is significant.
    pub chosen: Option<usize>,
}

/// Each of two candidates of round `round` (threshold `z_crit`) on top of the other, as the next
/// round of either branch of a fork would judge it: the members of `b`'s slot that the proposer
/// offers on top of `on_a`, the round's model with `a` accepted (refitted to convergence), and
/// those of `a`'s slot on top of `on_b` ([`proposed_on`]), each refitted by simulation on all
/// judging windows and compared with the model below it ([`tried`]), the member that would be
/// accepted chosen as in a round ([`OnTop::chosen`]). `[b on a, a on b]`.
pub fn on_top_of_each_other(
    ctx: &SelectCtx,
    (a, on_a): (&Candidate, &ModelState),
    (b, on_b): (&Candidate, &ModelState),
    (round, z_crit): (usize, f64),
) -> [OnTop; 2] {
    let members = [proposed_on(ctx, on_a, b), proposed_on(ctx, on_b, a)];
    let cur = [on_a, on_b];
    let tasks: Vec<(usize, &Candidate)> = (0..2)
        .flat_map(|n| members[n].iter().map(move |c| (n, c)))
        .collect();
    let judged = par_map(tasks.len(), |k| {
        let (n, c) = tasks[k];
        let st = evaluate(ctx, cur[n], c);
        (
            n,
            tried(ctx, cur[n], c.clone(), (None, st), (round, z_crit)),
        )
    });
    let mut out = [Vec::new(), Vec::new()];
    for (n, t) in judged {
        out[n].push(t);
    }
    out.map(|mut tried| {
        let passed = choose_members(ctx, &mut tried, z_crit);
        let chosen = passed
            .into_iter()
            .max_by(|&i, &j| tried[i].gain().total_cmp(&tried[j].gain()));
        OnTop { tried, chosen }
    })
}

/// The joint check of the close rivals `c.pair` of a round (see the module;
/// [`on_top_of_each_other`] at the round's threshold). When each is significant on top of the
/// other, of the two models with both (each one's member chosen on top of the other) the one
/// that predicts the held-out windows better is kept: the members of the effect on top as tried
/// there (the chosen member accepted, all marked [`Tried::on_top_of`]), the joint's record, and
/// the index in `round` of the effect below it. `None` (fork) when either is not significant,
/// or is not proposed there.
fn joint(
    ctx: &SelectCtx,
    round: &[Tried],
    c: &JointCheck,
    label: &str,
    progress: &dyn Observer,
) -> Option<(Vec<Tried>, Joint, usize)> {
    let (bi, ri) = c.pair;
    let z_crit = round[bi].z_crit;
    let (a, b) = (&round[bi].candidate, &round[ri].candidate);
    let [second_on_first, first_on_second] =
        on_top_of_each_other(ctx, (a, c.states.0), (b, c.states.1), (c.round, z_crit));
    let names = [a.effect.id, b.effect.id];
    for (on, this, other) in [
        (&second_on_first, names[1], names[0]),
        (&first_on_second, names[0], names[1]),
    ] {
        if on.tried.is_empty() {
            stage(
                progress,
                &format!(
                    "round {}{label} (joint check): {this} is not proposed on top of {other}",
                    c.round
                ),
            );
        }
        for t in &on.tried {
            report_tried(
                t,
                &format!("{label} (joint check, on top of {other})"),
                progress,
            );
        }
    }
    let (Some(sk), Some(fk)) = (second_on_first.chosen, first_on_second.chosen) else {
        return None;
    };
    // the two models with both effects, each member chosen on top of the other effect: the one
    // that predicts the held-out windows better is kept (the order decides nothing)
    fn held(t: &Tried) -> &super::judge::HeldOut {
        &t.state.as_ref().expect("judged").held
    }
    let order = compare(
        held(&second_on_first.tried[sk]),
        held(&first_on_second.tried[fk]),
        ctx.wins,
        ctx.runs,
    );
    let zg = |t: &Tried| t.cmp.map(|m| (m.z, m.gain)).expect("judged");
    let swap = order.gain > 0.0;
    let (below, on, k, other_z) = if swap {
        (ri, first_on_second, fk, zg(&second_on_first.tried[sk]))
    } else {
        (bi, second_on_first, sk, zg(&first_on_second.tried[fk]))
    };
    let term_names = |t: &Tried| t.candidate.terms.iter().map(|x| x.name()).collect();
    let first = round[below].candidate.effect.id;
    let second = on.tried[k].candidate.effect.id;
    stage(
        progress,
        &format!(
            "round {}{label}: {} and {} not told apart (held-out z {:.2} < {z_crit:.2}), but \
             each is significant on top of the other (z {:.2} and {:.2}): both accepted, {second} \
             on top of {first} (that model predicts the held-out windows better than the other \
             order's: χ² gain {:.1}, z {:.2})",
            c.round,
            names[0],
            names[1],
            c.round_z,
            zg(&on.tried[k]).0,
            other_z.0,
            order.gain.abs(),
            order.z.abs()
        ),
    );
    let j = Joint {
        round: c.round,
        first: first.to_string(),
        second: second.to_string(),
        first_terms: term_names(&round[below]),
        second_terms: term_names(&on.tried[k]),
        round_z: c.round_z,
        z_crit,
        second_on_first: zg(&on.tried[k]),
        first_on_second: other_z,
        order: (order.gain.abs(), order.z.abs()),
    };
    let mut on_top = on.tried;
    for (n, t) in on_top.iter_mut().enumerate() {
        t.on_top_of = Some(first);
        t.accepted = n == k;
        if n != k {
            t.state = None;
        }
    }
    Some((on_top, j, below))
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
        rivals: Rivals {
            forks,
            joints: kept.joints,
        },
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
