//! The navigator's succession (METHOD §8, "Navigator succession"): who leads the formation,
//! the rule by which every follower names the same successor when the leader is lost, and
//! how the successor takes over: it flies the navigator's path at its own slot, starting from
//! where the formation is and closing the gap to its slot on the path gently enough that the
//! UAVs leaning on it keep within their envelope.

use crate::dependency::DependencySet;
use crate::formation::Formation;
use crate::observation::UavId;
use crate::state::{self, State9};

/// Who leads the formation: the navigator, or after its loss the successor that flies the
/// navigator's path at its own slot (METHOD §8, "Navigator succession").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lead {
    /// The scenario's navigator (its slot stays the formation's reference).
    pub navigator: UavId,
    /// The UAV that leads now: the navigator, or its successor.
    pub leader: UavId,
}

impl Lead {
    /// The navigator leads.
    pub fn navigator(navigator: UavId) -> Self {
        Self { navigator, leader: navigator }
    }
}

/// The navigator's successor when the UAV leading now is lost, by a rule every follower can
/// evaluate from the formation and tables it flies (indexed by UAV) and from which UAVs still
/// fly: the flying UAV that leans on the lost leader with the highest degree, then the one
/// whose slot is nearest the leader's, then the lowest id. None when nobody flies.
pub fn successor(formation: &Formation, tables: &[DependencySet], lost: UavId, flying: &[bool]) -> Option<UavId> {
    let at = formation.slot(lost)?.offset_m;
    let rank = |u: usize| {
        let degree = tables.get(u).and_then(|t| t.degree(lost)).unwrap_or(0.0);
        let near = formation.slots.get(u).map_or(f64::INFINITY, |s| (s.offset_m - at).norm());
        (degree, near)
    };
    (0..formation.len())
        .filter(|&u| u != lost.index() && flying.get(u).copied().unwrap_or(false))
        .min_by(|&a, &b| {
            let ((da, na), (db, nb)) = (rank(a), rank(b));
            db.total_cmp(&da).then(na.total_cmp(&nb)).then(a.cmp(&b))
        })
        .map(|u| UavId(u as u32))
}

/// A take-over closes its gap with a time constant of this many of the followers' closing
/// times (`closing_time_s`, else one update period): slowly enough that the UAVs leaning on
/// the successor keep up, quickly enough that the formation stays near its path. Measured on
/// the paper's formation losing its navigator at 10, 60 and 80 s (200 runs each; runs passing,
/// largest distance from the path against its 6 m bound): 1.5: 24, 197, -; 2: 147, 197, 79
/// (5.1 m); 3: 154, 199, 156 (6.1 m); 4: 175, 200, 178 (7.6 m: runs off the path); 5: 112, 200,
/// 116 (9.1 m). The multirotor circuit, the fixed-wing echelon and the 20-UAV V pass every run
/// at 2 and at 3.
pub const TAKE_OVER_CLOSINGS: f64 = 3.0;

/// A successor's take-over: where the formation was and how it moved, relative to the
/// successor's slot on the path, when it took over, and how fast that gap closes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TakeOver {
    /// When it took over (s).
    pub at_s: f64,
    /// Its position less its slot's on the path then (m).
    pub gap_m: [f64; 3],
    /// Its velocity less its slot's then (m/s).
    pub gap_mps: [f64; 3],
    /// The time constant of the closing (s).
    pub over_s: f64,
}

impl TakeOver {
    /// A take-over at `at_s` by a UAV at `own` whose slot on the path is at `slot`, closing
    /// as the controller `params` would have it ([`TAKE_OVER_CLOSINGS`]).
    pub fn for_controller(at_s: f64, own: &State9, slot: &State9, params: &crate::ControllerParams) -> Self {
        let closing = params.closing_time_s.unwrap_or(params.dt_s);
        Self::new(at_s, own, slot, TAKE_OVER_CLOSINGS * closing)
    }

    /// A take-over at `at_s` by a UAV at `own` whose slot on the path is at `slot`, closing
    /// with time constant `over_s`.
    pub fn new(at_s: f64, own: &State9, slot: &State9, over_s: f64) -> Self {
        let gap_m = std::array::from_fn(|k| own[state::X + k] - slot[state::X + k]);
        let gap_mps = std::array::from_fn(|k| own[state::VX + k] - slot[state::VX + k]);
        Self { at_s, gap_m, gap_mps, over_s }
    }

    /// The successor's target at `t`: its slot on the path `slot`, moved by what is left of
    /// the gap, which closes as a critically damped second-order system from the gap and its
    /// rate at the take-over: `g(τ) = (g₀ + (ġ₀ + g₀/T)·τ)·e^(−τ/T)`, so that the successor
    /// goes on from where and how the formation flew, without a step in its velocity.
    pub fn target(&self, t: f64, slot: &State9) -> State9 {
        let (tau, big_t) = ((t - self.at_s).max(0.0), self.over_s);
        let decay = (-tau / big_t).exp();
        let mut s = *slot;
        for k in 0..3 {
            let (g0, v0) = (self.gap_m[k], self.gap_mps[k]);
            let b = v0 + g0 / big_t;
            s[state::X + k] += (g0 + b * tau) * decay;
            s[state::VX + k] += (v0 - b * tau / big_t) * decay;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formation::{FormationFrame, FormationSlot};

    #[test]
    fn the_successor_leans_most_on_the_leader_then_flies_nearest_it_then_has_the_lowest_id() {
        let slots = vec![
            FormationSlot::at(0.0, 0.0, 0.0),
            FormationSlot::at(-50.0, 50.0, 0.0),
            FormationSlot::at(-50.0, -50.0, 0.0),
            FormationSlot::at(-20.0, 0.0, 0.0),
        ];
        let f = Formation { slots, frame: FormationFrame::World };
        let t = |o: u32, r: &[(u32, f64)]| {
            DependencySet::new(UavId(o), 4, r.iter().map(|&(r, c)| (UavId(r), c)).collect()).expect("valid")
        };
        let mut tables =
            vec![DependencySet::default(), t(1, &[(0, 0.7)]), t(2, &[(0, 0.7)]), t(3, &[(0, 0.5), (1, 0.5)])];
        let all = [false, true, true, true];
        // 1 and 2 lean most on 0, equally near: the lower id.
        assert_eq!(successor(&f, &tables, UavId(0), &all), Some(UavId(1)));
        assert_eq!(successor(&f, &tables, UavId(0), &[false, false, true, true]), Some(UavId(2)));
        // Equal degrees: the nearest slot.
        tables[3] = t(3, &[(0, 0.7)]);
        assert_eq!(successor(&f, &tables, UavId(0), &all), Some(UavId(3)));
        assert_eq!(successor(&f, &tables, UavId(0), &[false; 4]), None);
    }

    #[test]
    fn a_take_over_starts_where_and_as_the_successor_flies_and_ends_on_its_slot() {
        let own = State9::from_column_slice(&[1.0, -2.0, 0.4, 70.0, 0.0, 2.0, 0.0, 0.0, 0.0]);
        let mut slot = State9::zeros();
        slot[state::VX] = 70.0;
        let t = TakeOver::new(10.0, &own, &slot, 5.0);
        let at = t.target(10.0, &slot);
        assert_eq!(at, own, "no step in position or velocity");
        // The rate is the derivative of the gap.
        let h = 1e-6;
        let (a, b) = (t.target(12.0 - h, &slot), t.target(12.0 + h, &slot));
        assert!(((b[state::Z] - a[state::Z]) / (2.0 * h) - t.target(12.0, &slot)[state::VZ]).abs() < 1e-6);
        let late = t.target(10.0 + 20.0 * 5.0, &slot);
        assert!((late - slot).norm() < 1e-6, "{late:?}");
    }
}
