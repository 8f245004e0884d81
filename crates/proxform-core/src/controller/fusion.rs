//! The robust fusion of the neighbours' estimates (METHOD §8, beyond the paper): each
//! neighbour's estimate X̂_ij of the UAV's own state, weighed against the median of those from
//! UAVs upstream before steps 2-3 average them. Owns the estimates' list and its scratch,
//! allocated once per controller and only when the fusion is on.

use crate::state::{State9, X};

/// One neighbour's part in steps 1-3 before the robust fusion weighs it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Implied {
    /// `X̂_ij − X_hold`.
    pub(super) x_hat: State9,
    /// Its weight f_j (1 when measured, fading while it coasts).
    pub(super) f: f64,
    /// Its dependency degree c_ij when it is a main reference.
    pub(super) c: Option<f64>,
    /// Whether it stands for an azimuth area (else a main reference outside the areas' nearest).
    pub(super) in_area: bool,
    /// Whether the robust fusion may weigh it down (not the navigator).
    pub(super) suspect: bool,
    /// Whether it counts in the robust fusion's median: its slot is no farther from the
    /// navigator's than the UAV's own (it does not lean on this UAV through the formation).
    pub(super) upstream: bool,
}

/// The robust fusion's working memory.
#[derive(Debug, Clone, Default)]
pub(super) struct Fusion {
    pub(super) implied: Vec<Implied>,
    pub(super) scratch: Vec<f64>,
}

impl Fusion {
    /// Robust fusion (METHOD §8): scales each estimate's weight by 1 within `gate`·Δ of a
    /// reference position, 0 beyond 2·`gate`·Δ, linearly between (on its farthest axis, Δ the
    /// permissible errors); the navigator's keeps its weight. The reference, from the
    /// estimates of the UAVs upstream (see [`super::ProximityController::with_navigator`]):
    /// their per-axis median when there are at least three; else the navigator's estimate
    /// when it is perceived; else, with two, the per-axis median of theirs and the UAV's own
    /// course (zero deviation); with one, its estimate; with none, nothing is weighed.
    /// Returns how many it left out. Should it leave out every one (medians from different
    /// estimates on each axis), it keeps them all: the fusion then cannot tell which one is
    /// wrong.
    pub(super) fn weigh(&mut self, delta: &State9, gate: f64) -> u16 {
        let Self { implied, scratch } = self;
        let distance =
            |a: &State9, b: &[f64; 3]| (0..3).map(|k| (a[X + k] - b[k]).abs() / delta[X + k]).fold(0.0, f64::max);
        let position = |n: &Implied| [n.x_hat[X], n.x_hat[X + 1], n.x_hat[X + 2]];
        let upstream = implied.iter().filter(|n| n.upstream).count();
        let reference = if upstream >= 3 {
            median(implied.iter().filter(|n| n.upstream), scratch)
        } else if let Some(nav) = implied.iter().find(|n| !n.suspect) {
            position(nav)
        } else {
            let mut ups = implied.iter().filter(|n| n.upstream);
            match (ups.next(), ups.next()) {
                (Some(a), None) => position(a),
                // Two that may disagree: the UAV's own course (a deviation of zero) breaks the tie,
                // so that a reference that starts to wander is left, not followed.
                (Some(a), Some(b)) => {
                    let (pa, pb) = (position(a), position(b));
                    std::array::from_fn(|k| pa[k].max(pb[k]).min(0.0_f64.max(pa[k].min(pb[k]))))
                }
                _ => return 0,
            }
        };
        scratch.clear();
        scratch.extend(implied.iter().map(|n| {
            if !n.suspect {
                return 1.0;
            }
            (2.0 - distance(&n.x_hat, &reference) / gate).clamp(0.0, 1.0)
        }));
        let left_out = scratch.iter().filter(|&&w| w == 0.0).count();
        if left_out == implied.len() {
            return 0;
        }
        for (n, &w) in implied.iter_mut().zip(scratch.iter()) {
            n.f *= w;
        }
        left_out as u16
    }
}

/// Per-axis median position of `estimates` (at least one), sorting in `scratch`.
fn median<'a>(estimates: impl Iterator<Item = &'a Implied> + Clone, scratch: &mut Vec<f64>) -> [f64; 3] {
    let mut m = [0.0; 3];
    for (k, v) in m.iter_mut().enumerate() {
        scratch.clear();
        scratch.extend(estimates.clone().map(|n| n.x_hat[X + k]));
        scratch.sort_unstable_by(f64::total_cmp);
        let h = scratch.len() / 2;
        *v = if scratch.len() % 2 == 1 { scratch[h] } else { 0.5 * (scratch[h - 1] + scratch[h]) };
    }
    m
}
