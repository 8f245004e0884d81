//! What the controller's step reads and writes of a UAV's neighbour tracks (METHOD §3): the
//! one seam between the method and how an engine stores its tracks. The step
//! ([`super::UavView::step`]) is written once over this trait; [`NeighbourTracks`] (f64
//! records, every predictor) is the reference store, and an engine may keep its own records
//! (compact ones for a large swarm) behind it.
//!
//! Times are seconds on the UAV's clock, positions in the frame its observations are given in.

use crate::observation::{Observation, UavId};
use crate::predictor::NeighbourTracks;
use crate::state::State9;

/// A UAV's tracks of its neighbours, as the controller's step uses them.
pub trait Tracks {
    /// Feeds observation `obs` (taken at `now − obs.age_s`) and returns the neighbour's
    /// predicted state at `now + horizon_s` (F·X_j).
    fn predict(&mut self, obs: &Observation, now: f64, horizon_s: f64) -> State9;

    /// Number of track slots (some may be free).
    fn slots(&self) -> usize;

    /// The slot of `id`'s track, if it has one (a UAV has at most one).
    fn slot_of(&self, id: UavId) -> Option<usize>;

    /// The neighbour of slot `s` if its track can coast at `now`: last heard before `now`, no
    /// longer ago than `max_s`, and measured no longer ago than `max_age_s`.
    fn coasting(&self, s: usize, now: f64, max_s: f64, max_age_s: f64) -> Option<UavId>;

    /// Seconds since a report of slot `s` last arrived, at `now`.
    fn missing(&self, s: usize, now: f64) -> f64;

    /// Slot `s`'s state brought forward to time `t` (a coasting neighbour).
    fn state_at(&self, s: usize, t: f64) -> State9;

    /// Whether reports are brought forward by the mission plan beyond a period.
    fn carries(&self) -> bool;

    /// What the tracks know of `id` at `now`: its filtered state at its last measurement and
    /// that measurement's age (s); None when untracked, not heard within the timeout, or
    /// measured more than `max_age_s` ago.
    fn report(&self, id: UavId, now: f64, max_age_s: f64) -> Option<(State9, f64)>;

    /// Whether `id`'s last report came from the owner's own sensors within `max_s` of `now`
    /// (used with relative sensing only).
    fn heard_onboard(&self, id: UavId, now: f64, max_s: f64) -> bool;

    /// Whether any neighbour's last report came from the owner's own sensors within `max_s`.
    fn any_heard_onboard(&self, now: f64, max_s: f64) -> bool;
}

impl Tracks for NeighbourTracks {
    #[inline]
    fn predict(&mut self, obs: &Observation, now: f64, horizon_s: f64) -> State9 {
        NeighbourTracks::predict(self, obs, now, horizon_s)
    }
    #[inline]
    fn slots(&self) -> usize {
        NeighbourTracks::slots(self)
    }
    #[inline]
    fn slot_of(&self, id: UavId) -> Option<usize> {
        NeighbourTracks::slot_of(self, id)
    }
    #[inline]
    fn coasting(&self, s: usize, now: f64, max_s: f64, max_age_s: f64) -> Option<UavId> {
        NeighbourTracks::coasting(self, s, now, max_s, max_age_s)
    }
    #[inline]
    fn missing(&self, s: usize, now: f64) -> f64 {
        NeighbourTracks::missing(self, s, now)
    }
    #[inline]
    fn state_at(&self, s: usize, t: f64) -> State9 {
        NeighbourTracks::state_at(self, s, t)
    }
    #[inline]
    fn carries(&self) -> bool {
        NeighbourTracks::carries(self)
    }
    #[inline]
    fn report(&self, id: UavId, now: f64, max_age_s: f64) -> Option<(State9, f64)> {
        NeighbourTracks::report(self, id, now, max_age_s)
    }
    #[inline]
    fn heard_onboard(&self, id: UavId, now: f64, max_s: f64) -> bool {
        NeighbourTracks::heard_onboard(self, id, now, max_s)
    }
    #[inline]
    fn any_heard_onboard(&self, now: f64, max_s: f64) -> bool {
        NeighbourTracks::any_heard_onboard(self, now, max_s)
    }
}
