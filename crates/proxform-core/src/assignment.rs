//! Which UAV flies which slot when the UAVs are not bound to fixed slots (METHOD §8, "Slot
//! assignment"): the assignment of UAVs to slots with the least total (or the least largest)
//! distance, and the formation after a loss, with the vacated slot chosen among those no
//! other slot leans on and the survivors re-assigned. The assignment solver is Kuhn-Munkres
//! from the `pathfinding` crate, on distances in millimetres (exact enough, and far from
//! `i64`'s range for flights up to 10^9 m).
//!
//! A formation relabelled by an assignment is an ordinary [`Formation`] indexed by UAV (UAV
//! `u` has the slot `slot_of[u]` of the formation it came from) with every UAV's dependency
//! table rewritten from slots to the UAVs now flying them ([`relabel`]).

use std::sync::Arc;

use pathfinding::kuhn_munkres::kuhn_munkres_min;
use pathfinding::matrix::Matrix;

use crate::dependency::DependencySet;
use crate::formation::Formation;
use crate::observation::UavId;
pub use crate::succession::Lead;

/// What an assignment minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AssignBy {
    /// The total distance from the UAVs to their slots.
    #[default]
    Total,
    /// The largest distance from a UAV to its slot (then the total among the assignments
    /// with that largest distance): the formation is complete soonest.
    Largest,
}

impl AssignBy {
    /// Its name in scenario files.
    pub fn label(self) -> &'static str {
        match self {
            AssignBy::Total => "total",
            AssignBy::Largest => "largest",
        }
    }
}

/// The most UAVs an assignment by the total distance takes: the solver is cubic in them (on a
/// 2-core test machine 1 000 UAVs took ~1 s, 2 000 ~5 s, 3 000 ~25 s, 10 000 hours).
pub const MAX_ASSIGNED_BY_TOTAL: usize = 2_000;

/// The most UAVs an assignment by the largest distance takes: it solves about twenty
/// problems of that size (a bisection over the distances), then one more.
pub const MAX_ASSIGNED_BY_LARGEST: usize = 500;

/// The most UAVs `by` assigns in seconds: once (a start), or after a loss, where up to
/// [`MAX_CANDIDATES`] assignments are solved (each vacated slot a candidate) and the bound is
/// that many times smaller in work (2.5 times in UAVs). A scenario with more is refused when
/// it is read, with this limit named, rather than left to run for hours.
pub fn max_assigned(by: AssignBy, after_loss: bool) -> usize {
    let once = match by {
        AssignBy::Total => MAX_ASSIGNED_BY_TOTAL,
        AssignBy::Largest => MAX_ASSIGNED_BY_LARGEST,
    };
    match after_loss {
        false => once,
        // Cubic work: MAX_CANDIDATES solves of n UAVs cost what one of n · 16^(1/3) does.
        true => (once as f64 / (MAX_CANDIDATES as f64).cbrt()).floor() as usize,
    }
}

/// Millimetres: the solver's integer costs.
fn mm(d_m: f64) -> i64 {
    (d_m * 1000.0).round().clamp(0.0, 1e15) as i64
}

/// For each of `rows` UAVs, the column (slot, of `cols` ≥ `rows`) it takes, minimising `by`
/// over the distances `distance_m(row, col)` (m, finite and ≥ 0).
pub fn assign(rows: usize, cols: usize, distance_m: impl Fn(usize, usize) -> f64, by: AssignBy) -> Vec<usize> {
    if rows == 0 {
        return Vec::new();
    }
    debug_assert!(rows <= cols, "{rows} UAVs for {cols} slots");
    let cost = Matrix::from_fn(rows, cols, |(r, c)| mm(distance_m(r, c)));
    match by {
        AssignBy::Total => kuhn_munkres_min(&cost).1,
        AssignBy::Largest => {
            // The bottleneck: the least threshold under which every row still has a column of
            // its own (a zero-cost assignment of the indicator "above the threshold").
            let mut levels: Vec<i64> = cost.values().copied().collect();
            levels.sort_unstable();
            levels.dedup();
            let feasible = |limit: i64| {
                let above = Matrix::from_fn(rows, cols, |(r, c)| i64::from(cost[(r, c)] > limit));
                kuhn_munkres_min(&above).0 == 0
            };
            let (mut lo, mut hi) = (0, levels.len() - 1);
            while lo < hi {
                let mid = (lo + hi) / 2;
                if feasible(levels[mid]) {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            let limit = levels[lo];
            // Least total among the assignments within the bottleneck: costs above it are
            // made dearer than any total within it.
            let over = (rows as i64).saturating_mul(limit).saturating_add(1);
            let bounded = Matrix::from_fn(rows, cols, |(r, c)| {
                let v = cost[(r, c)];
                if v > limit {
                    over
                } else {
                    v
                }
            });
            kuhn_munkres_min(&bounded).1
        }
    }
}

/// Candidate vacated slots evaluated by a full assignment after a loss; beyond this many, the
/// candidates nearest the lost UAVs' slots.
pub const MAX_CANDIDATES: usize = 16;

/// After losses: the slot of every UAV (`slot_of[u]`, a permutation of the formation's
/// slots), given where each UAV flies, which still fly, and where each slot is now.
///
/// As many slots as UAVs were lost are vacated, one at a time, each among the slots that the
/// fewest remaining slots lean on (the formation's edge: in the paper's tables and the derived
/// ones, those nobody leans on), choosing the one that leaves the least assignment cost; the
/// flying followers then take the remaining slots by `by`. A lost UAV's slot at the edge is
/// simply left empty (nobody moves); a lost UAV inside the formation is replaced, the edge
/// closing in. The navigator keeps its slot. Lost UAVs get the vacated slots.
pub fn after_loss(
    formation: &Formation,
    tables: &[DependencySet],
    navigator: UavId,
    (slot_of, flying): (&[usize], &[bool]),
    (uav_at, slot_at): (&[[f64; 3]], &[[f64; 3]]),
    by: AssignBy,
) -> Vec<usize> {
    let n = formation.len();
    let nav_slot = slot_of[navigator.index()];
    let uavs: Vec<usize> = (0..n).filter(|&u| u != navigator.index() && flying[u]).collect();
    let mut open: Vec<usize> = (0..n).filter(|&s| s != nav_slot).collect();
    let distance = |u: usize, s: usize| {
        let (a, b) = (uav_at[u], slot_at[s]);
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let cost_of = |open: &[usize]| -> (f64, f64, Vec<usize>) {
        let pick = assign(uavs.len(), open.len(), |r, c| distance(uavs[r], open[c]), by);
        let d: Vec<f64> = pick.iter().enumerate().map(|(r, &c)| distance(uavs[r], open[c])).collect();
        let total = d.iter().sum::<f64>();
        let largest = d.iter().copied().fold(0.0, f64::max);
        (total, largest, pick)
    };
    let lost_slots: Vec<usize> = (0..n).filter(|&u| u != navigator.index() && !flying[u]).map(|u| slot_of[u]).collect();
    while open.len() > uavs.len() {
        // Dependents of each open slot among the open slots and the navigator's.
        let leaned_on =
            |s: usize| open.iter().filter(|&&o| tables[o].refs().iter().any(|(r, _)| r.index() == s)).count();
        let fewest = open.iter().map(|&s| leaned_on(s)).min().unwrap_or(0);
        let mut candidates: Vec<usize> = open.iter().copied().filter(|&s| leaned_on(s) == fewest).collect();
        if candidates.len() > MAX_CANDIDATES {
            let near = |s: usize| {
                lost_slots
                    .iter()
                    .map(|&l| (formation.slots[s].offset_m - formation.slots[l].offset_m).norm())
                    .fold(f64::INFINITY, f64::min)
            };
            candidates.sort_by(|a, b| near(*a).total_cmp(&near(*b)).then(a.cmp(b)));
            candidates.truncate(MAX_CANDIDATES);
        }
        let key = |c: &(f64, f64, Vec<usize>)| match by {
            AssignBy::Total => (c.0, c.1),
            AssignBy::Largest => (c.1, c.0),
        };
        let mut best: Option<(usize, (f64, f64))> = None;
        for &v in &candidates {
            let rest: Vec<usize> = open.iter().copied().filter(|&s| s != v).collect();
            let k = key(&cost_of(&rest));
            // Ties go to the lowest slot number: the result does not depend on the order.
            if best.is_none_or(|(_, b)| k.0 < b.0 - 1e-9 || ((k.0 - b.0).abs() <= 1e-9 && k.1 < b.1 - 1e-9)) {
                best = Some((v, k));
            }
        }
        let Some((v, _)) = best else { break };
        open.retain(|&s| s != v);
    }
    let mut out = slot_of.to_vec();
    let (_, _, pick) = cost_of(&open);
    for (r, &u) in uavs.iter().enumerate() {
        out[u] = open[pick[r]];
    }
    // The lost UAVs take the slots nobody flies.
    let mut taken = vec![false; n];
    taken[nav_slot] = true;
    for &u in &uavs {
        taken[out[u]] = true;
    }
    let mut free = (0..n).filter(|&s| !taken[s]);
    for u in (0..n).filter(|&u| u != navigator.index() && !flying[u]) {
        if let Some(s) = free.next() {
            out[u] = s;
        }
    }
    out
}

/// Slots re-assigned in flight, as every agent is handed them: which slot each UAV flies,
/// which UAVs still fly, who leads, and the formation in force relabelled ([`relabel`]).
#[derive(Debug, Clone)]
pub struct Reassignment {
    /// The slot (of the formation as the scenario gives it) each UAV flies.
    pub slot_of: Arc<[usize]>,
    /// Which UAVs still fly (the others are nobody's reference).
    pub flying: Arc<[bool]>,
    /// Who leads the formation.
    pub lead: Lead,
    /// Whether any UAV's slot or the formation changed with it (false: only the leader did,
    /// and the agents keep their tracks).
    pub moved: bool,
    /// The formation in force, indexed by UAV.
    pub formation: Arc<Formation>,
    /// Every UAV's table in it.
    pub tables: Arc<[DependencySet]>,
}

impl Reassignment {
    /// `formation` (indexed by slot, with its `tables`) flown by UAVs assigned `slot_of`, led
    /// by `lead`.
    pub fn new(
        formation: &Formation,
        tables: &[DependencySet],
        slot_of: Vec<usize>,
        flying: Vec<bool>,
        lead: Lead,
    ) -> Self {
        let (f, t) = relabel(formation, tables, &slot_of, &flying, lead);
        Self {
            slot_of: slot_of.into(),
            flying: flying.into(),
            lead,
            moved: true,
            formation: Arc::new(f),
            tables: t.into(),
        }
    }

    /// The same, stating whether slots moved with it.
    pub fn moving(self, moved: bool) -> Self {
        Self { moved, ..self }
    }
}

/// The formation `formation` (indexed by slot) flown by UAVs assigned `slot_of` (a
/// permutation): indexed by UAV, each UAV's table rewritten to the UAVs flying the slots its
/// slot leaned on, leaving out the UAVs not `flying` (the degrees of the others keep their
/// ratios: the method's mean is normalised). A reference to the navigator's slot while the
/// navigator is lost goes to the leader (its degree added to the leader's, if the table
/// already names it).
pub fn relabel(
    formation: &Formation,
    tables: &[DependencySet],
    slot_of: &[usize],
    flying: &[bool],
    lead: Lead,
) -> (Formation, Vec<DependencySet>) {
    let n = formation.len();
    let mut uav_of = vec![usize::MAX; n];
    for (u, &s) in slot_of.iter().enumerate() {
        uav_of[s] = u;
    }
    let (navigator, leader) = (lead.navigator.index(), lead.leader.index());
    let slots = slot_of.iter().map(|&s| formation.slots[s]).collect();
    let tables = slot_of
        .iter()
        .enumerate()
        .map(|(u, &s)| {
            let mut refs: Vec<(UavId, f64)> = Vec::new();
            for &(r, c) in tables.get(s).map(|t| t.refs()).unwrap_or(&[]) {
                let Some(&v) = uav_of.get(r.index()) else { continue };
                let v = if v == navigator && !flying.get(v).copied().unwrap_or(false) { leader } else { v };
                if v >= n || v == u || !flying.get(v).copied().unwrap_or(false) {
                    continue;
                }
                match refs.iter_mut().find(|(w, _)| w.index() == v) {
                    Some(e) => e.1 += c,
                    None => refs.push((UavId(v as u32), c)),
                }
            }
            // The references are distinct UAVs of the formation, other than the owner, with
            // the degrees of a checked table.
            DependencySet::new(UavId(u as u32), n, refs).unwrap_or_default()
        })
        .collect();
    (Formation { slots, frame: formation.frame }, tables)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formation::{FormationFrame, FormationSlot};

    fn line(p: &[f64]) -> Vec<[f64; 3]> {
        p.iter().map(|&x| [x, 0.0, 0.0]).collect()
    }

    #[test]
    fn the_largest_distance_is_least_where_the_total_is_not() {
        // UAVs at 0 and 10, slots at 9 and 19: total pairs them straight (9 + 9 = 18, largest
        // 9) or crossed (19 + 1 = 20, largest 19); slots at 1 and 11 with UAVs at 0 and 12:
        // straight 1 + 1; crossed 11 + 11.
        let (u, s) = (line(&[0.0, 10.0]), line(&[9.0, 19.0]));
        let d = |r: usize, c: usize| (u[r][0] - s[c][0]).abs();
        assert_eq!(assign(2, 2, d, AssignBy::Total), vec![0, 1]);
        assert_eq!(assign(2, 2, d, AssignBy::Largest), vec![0, 1]);
        // UAVs at 0, 1, 2; slots at 2, 3, 100: total 2+2+98 = 102 either way it pairs 2 with
        // 100 or 0 with 100; the largest is least (98) when the UAV nearest 100 goes there.
        let (u, s) = (line(&[0.0, 1.0, 2.0]), line(&[2.0, 3.0, 100.0]));
        let d = |r: usize, c: usize| (u[r][0] - s[c][0]).abs();
        let largest = |p: &[usize]| p.iter().enumerate().map(|(r, &c)| d(r, c)).fold(0.0, f64::max);
        let total = |p: &[usize]| p.iter().enumerate().map(|(r, &c)| d(r, c)).sum::<f64>();
        let by_largest = assign(3, 3, d, AssignBy::Largest);
        assert_eq!(largest(&by_largest), 98.0, "{by_largest:?}");
        assert_eq!(total(&by_largest), total(&assign(3, 3, d, AssignBy::Total)));
        // Random cases against brute force over every permutation.
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) as f64 / (1u64 << 31) as f64 * 1000.0
        };
        for _ in 0..200 {
            let (u, s): (Vec<f64>, Vec<f64>) = ((0..5).map(|_| next()).collect(), (0..5).map(|_| next()).collect());
            let d = |r: usize, c: usize| (u[r] - s[c]).abs();
            let mut best = (f64::INFINITY, f64::INFINITY);
            permutations(5, &mut |p| {
                let l = p.iter().enumerate().map(|(r, &c)| mm(d(r, c))).max().unwrap_or(0);
                let t: i64 = p.iter().enumerate().map(|(r, &c)| mm(d(r, c))).sum();
                let k = (l as f64, t as f64);
                if k < best {
                    best = k;
                }
            });
            let p = assign(5, 5, d, AssignBy::Largest);
            let l = p.iter().enumerate().map(|(r, &c)| mm(d(r, c))).max().unwrap_or(0);
            let t: i64 = p.iter().enumerate().map(|(r, &c)| mm(d(r, c))).sum();
            assert_eq!((l as f64, t as f64), best);
        }
    }

    fn permutations(n: usize, f: &mut impl FnMut(&[usize])) {
        fn go(k: usize, p: &mut Vec<usize>, f: &mut impl FnMut(&[usize])) {
            if k == p.len() {
                f(p);
                return;
            }
            for i in k..p.len() {
                p.swap(k, i);
                go(k + 1, p, f);
                p.swap(k, i);
            }
        }
        go(0, &mut (0..n).collect(), f);
    }

    /// A V of 5: the navigator 0 ahead, 1 and 2 behind it leaning on it, 3 behind 1 and 4
    /// behind 2, each leaning on the one ahead (3 and 4 are the edge).
    fn v5() -> (Formation, Vec<DependencySet>) {
        let slots = vec![
            FormationSlot::at(0.0, 0.0, 0.0),
            FormationSlot::at(-50.0, 50.0, 0.0),
            FormationSlot::at(-50.0, -50.0, 0.0),
            FormationSlot::at(-100.0, 100.0, 0.0),
            FormationSlot::at(-100.0, -100.0, 0.0),
        ];
        let t = |o: u32, r: &[u32]| DependencySet::new(UavId(o), 5, r.iter().map(|&r| (UavId(r), 1.0)).collect());
        let tables = vec![
            DependencySet::default(),
            t(1, &[0]).expect("valid"),
            t(2, &[0]).expect("valid"),
            t(3, &[1]).expect("valid"),
            t(4, &[2]).expect("valid"),
        ];
        (Formation { slots, frame: FormationFrame::World }, tables)
    }

    fn at_slots(f: &Formation) -> Vec<[f64; 3]> {
        f.slots.iter().map(|s| [s.offset_m.x, s.offset_m.y, s.offset_m.z]).collect()
    }

    #[test]
    fn a_loss_at_the_edge_moves_nobody_and_one_inside_is_filled_from_the_edge() {
        let (f, tables) = v5();
        let slots = at_slots(&f);
        let ids: Vec<usize> = (0..5).collect();
        // UAV 3 (an edge slot) lost: nobody moves.
        let flying = [true, true, true, false, true];
        let out = after_loss(&f, &tables, UavId(0), (&ids, &flying), (&slots, &slots), AssignBy::Total);
        assert_eq!(out, ids);
        // UAV 1 (leaned on by 3) lost: 3 moves up into slot 1, slot 3 is left empty.
        let flying = [true, false, true, true, true];
        let out = after_loss(&f, &tables, UavId(0), (&ids, &flying), (&slots, &slots), AssignBy::Total);
        assert_eq!(out, vec![0, 3, 2, 1, 4]);
        let (g, t) = relabel(&f, &tables, &out, &flying, Lead::navigator(UavId(0)));
        assert_eq!(g.slots[3], f.slots[1], "UAV 3 flies slot 1");
        assert_eq!(t[3].refs(), &[(UavId(0), 1.0)], "and leans on the navigator as slot 1 did");
        assert!(t[4].refs() == [(UavId(2), 1.0)] && t[2].refs() == [(UavId(0), 1.0)]);
        // A lost UAV is never a reference.
        let flying = [true, false, true, true, true];
        let (_, t) = relabel(&f, &tables, &ids, &flying, Lead::navigator(UavId(0)));
        assert!(t[3].is_empty(), "{:?}", t[3]);
    }

    #[test]
    fn a_lost_navigators_dependents_lean_on_its_successor() {
        // Navigator 0 lost, 1 succeeds: 2 leaned on 0 and now on 1; 3 leaned on 1 and still
        // does; 1's own table (on 0) is left empty (it leads).
        let (f, mut tables) = v5();
        tables[3] = DependencySet::new(UavId(3), 5, vec![(UavId(0), 0.4), (UavId(1), 0.6)]).expect("valid");
        let ids: Vec<usize> = (0..5).collect();
        let flying = [false, true, true, true, true];
        let lead = Lead { navigator: UavId(0), leader: UavId(1) };
        let (_, t) = relabel(&f, &tables, &ids, &flying, lead);
        assert!(t[1].is_empty());
        assert_eq!(t[2].refs(), &[(UavId(1), 1.0)]);
        // Both of 3's references are now UAV 1: one entry, the degrees added.
        assert_eq!(t[3].refs(), &[(UavId(1), 1.0)]);
        assert_eq!(t[4].refs(), &[(UavId(2), 1.0)]);
        // While the navigator flies, nothing is redirected.
        let (_, t) = relabel(&f, &tables, &ids, &[true; 5], lead);
        assert_eq!(t[2].refs(), &[(UavId(0), 1.0)]);
    }

    #[test]
    fn the_largest_objective_spreads_the_move_when_the_total_would_not() {
        // A row of slots 0 (navigator), 1..=4 at 10, 20, 30, 40 m, each leaning on the one
        // before: UAV 1 lost. Total: UAVs 2, 3, 4 each move up 10 m (30 m, largest 10) or
        // UAV 4 jumps to slot 1 (30 m, largest 30): the same total, the largest objective
        // takes the shift.
        let slots: Vec<FormationSlot> = (0..5).map(|k| FormationSlot::at(-10.0 * k as f64, 0.0, 0.0)).collect();
        let tables: Vec<DependencySet> = (0..5u32)
            .map(|k| {
                if k == 0 {
                    DependencySet::default()
                } else {
                    DependencySet::new(UavId(k), 5, vec![(UavId(k - 1), 1.0)]).expect("valid")
                }
            })
            .collect();
        let f = Formation { slots, frame: FormationFrame::World };
        let at = at_slots(&f);
        let ids: Vec<usize> = (0..5).collect();
        let flying = [true, false, true, true, true];
        let out = after_loss(&f, &tables, UavId(0), (&ids, &flying), (&at, &at), AssignBy::Largest);
        assert_eq!(&out[2..], &[1, 2, 3], "{out:?}");
        assert_eq!(out[1], 4, "the lost UAV takes the vacated slot");
    }
}
