//! Dependency tables derived from the formation's geometry.
//!
//! Each UAV takes as main references its `k` nearest slots among those strictly closer to the
//! navigator's slot (within `max_distance_m`), with degrees proportional to 1/distance and
//! normalised to sum to 1. Every reference is closer to the navigator than its owner, so the
//! references form a tree-like graph without cycles that leads to the navigator. Uses the
//! neighbour grid: O(N) for N slots.

use proxform_core::dependency::TableBuilder;
use proxform_core::{ConfigError, DependencySet, FormationSlot, UavId};

use proxform_core::grid::NeighbourGrid;

/// Derives every UAV's dependency table (the navigator's is empty).
///
/// With `navigator_degree` > 0 every follower also names the navigator (heard over the
/// radio when out of sensing range) with that degree; the local degrees share the rest.
pub fn derive(
    slots: &[FormationSlot],
    navigator: UavId,
    k: usize,
    max_distance_m: f64,
    navigator_degree: f64,
) -> Result<Vec<DependencySet>, ConfigError> {
    let n = slots.len();
    let nav = slots.get(navigator.index()).ok_or(ConfigError::UnknownUav { id: navigator, size: n })?.offset_m;
    let to_nav: Vec<f64> = slots.iter().map(|s| (s.offset_m - nav).norm()).collect();
    let at = |i: usize| [slots[i].offset_m.x, slots[i].offset_m.y, slots[i].offset_m.z];
    // Each UAV's k nearest candidates (the slots closer to the navigator), kept in one flat
    // array of k per UAV, sorted, with how many each has: the search radius grows by doubling
    // up to `max_distance_m`, and only for the UAVs still short of k candidates, so a generous
    // maximum does not make every search cover the whole formation. One scratch list serves
    // every search (a list per UAV left the heap fragmented for a swarm of millions).
    // No UAV has more references than the others.
    let k = k.min(n);
    let mut best: Vec<(f64, u32)> = vec![(f64::INFINITY, u32::MAX); n * k];
    let mut count: Vec<u32> = vec![0; n];
    let mut scratch: Vec<(f64, u32)> = Vec::new();
    let mut pending: Vec<usize> = (0..n).filter(|&i| i != navigator.index()).collect();
    let spread = to_nav.iter().copied().fold(0.0, f64::max);
    let mut radius = max_distance_m.min((spread / (n as f64).sqrt().max(1.0)).max(1.0) * 4.0);
    let mut grid = NeighbourGrid::new();
    while !pending.is_empty() {
        let last = radius >= max_distance_m;
        grid.rebuild((0..n).map(at), radius);
        pending.retain(|&i| {
            scratch.clear();
            grid.for_each_within(at(i), radius, |j, _, d2| {
                if to_nav[j as usize] < to_nav[i] - 1e-9 {
                    scratch.push((d2.sqrt(), j));
                }
            });
            let enough = scratch.len() >= k;
            scratch.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            scratch.truncate(k);
            best[i * k..i * k + scratch.len()].copy_from_slice(&scratch);
            count[i] = scratch.len() as u32;
            !enough && !last
        });
        radius = (2.0 * radius).min(max_distance_m);
    }
    let mut out = TableBuilder::new(n, n * (k + 1));
    let mut refs: Vec<(UavId, f64)> = Vec::with_capacity(k + 1);
    for i in 0..n {
        if i == navigator.index() {
            out.push(navigator, &[])?;
            continue;
        }
        let cands = &best[i * k..i * k + count[i] as usize];
        let nav_in_cands = cands.iter().any(|c| c.1 == navigator.0);
        let local_share = if navigator_degree > 0.0 && !nav_in_cands { 1.0 - navigator_degree } else { 1.0 };
        let total: f64 = cands.iter().map(|(d, _)| 1.0 / d.max(1e-9)).sum();
        refs.clear();
        refs.extend(cands.iter().map(|&(d, j)| (UavId(j), local_share * (1.0 / d.max(1e-9)) / total)));
        if navigator_degree > 0.0 && !nav_in_cands {
            refs.push((navigator, if refs.is_empty() { 1.0 } else { navigator_degree }));
        }
        out.push(UavId(i as u32), &refs)?;
    }
    Ok(out.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_lead_to_the_navigator() {
        let slots: Vec<FormationSlot> =
            (0..30).map(|i| FormationSlot::at(-(i / 5) as f64 * 50.0, ((i % 5) as f64 - 2.0) * 50.0, 0.0)).collect();
        let nav = UavId(2); // front row, centre
        let deps = derive(&slots, nav, 3, 80.0, 0.0).expect("valid");
        assert!(deps[2].is_empty());
        // One allocation for the whole formation, not one per UAV.
        assert!(deps.iter().all(|d| d.shares_entries_with(&deps[0])));
        for (i, d) in deps.iter().enumerate() {
            if i == 2 {
                continue;
            }
            assert!(!d.is_empty(), "UAV {i} has no reference");
            let sum: f64 = d.refs().iter().map(|r| r.1).sum();
            assert!((sum - 1.0).abs() < 1e-12);
            // Following the strongest reference always reaches the navigator.
            let mut at = i;
            for _ in 0..30 {
                if at == 2 {
                    break;
                }
                let best = deps[at].refs().iter().max_by(|a, b| a.1.total_cmp(&b.1)).expect("non-empty");
                at = best.0.index();
            }
            assert_eq!(at, 2, "UAV {i} does not lead to the navigator");
        }
        // The UAV right behind the navigator leans on it most.
        assert_eq!(deps[7].refs()[0].0, UavId(2));
        // A generous maximum finds the same nearest references as a tight one.
        let wide = derive(&slots, nav, 3, 1e6, 0.0).expect("valid");
        let tight = derive(&slots, nav, 3, 80.0, 0.0).expect("valid");
        let fits = (0..30).filter(|&i| tight[i].refs().len() == 3).count();
        assert!(fits > 20);
        for i in 0..30 {
            if tight[i].refs().len() == 3 {
                assert_eq!(wide[i], tight[i], "UAV {i}");
            }
        }
    }
}
