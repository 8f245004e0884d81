//! Where the UAVs start: in their slots (the default, and the paper's), scattered at random in
//! a box or a disc around the formation, or at explicit positions. Random starts are drawn by
//! the simulator for each run (a seeded stream of its own), so that every run of a batch starts
//! differently and the same seed starts the same way. With `assign_slots`, the followers are
//! not bound to the slots nearest their draw order: the drawn starts are assigned to the slots
//! so that the total (or, with `assign_by = "largest"`, the largest) distance from start to
//! slot is least ([`proxform_core::assignment`]).

use proxform_core::assignment::AssignBy;
use proxform_core::UavId;

/// How the followers are placed at t = 0 (the navigator starts on its path).
#[derive(Debug, Clone, PartialEq)]
pub enum Placement {
    /// Every UAV in its slot, on the navigator's initial state.
    Slots,
    /// Uniformly in a box centred on the followers' slots' centre: its size along the world
    /// x (the initial course), y (left) and z (up), m.
    Box {
        /// Size along x, y and z (m).
        size_m: [f64; 3],
        /// Slots assigned to the drawn starts, minimising this (None: in draw order).
        assign: Option<AssignBy>,
    },
    /// Uniformly in a horizontal disc centred on the followers' slots' centre, spread evenly
    /// over a height band.
    Disc {
        /// Radius (m).
        radius_m: f64,
        /// Height of the band (m).
        height_m: f64,
        /// Slots assigned to the drawn starts, minimising this (None: in draw order).
        assign: Option<AssignBy>,
    },
    /// On the ground in a row across the initial course (along the world y axis), centred
    /// under the centre of the followers' slots, standing still and level: a take-off.
    Row {
        /// Distance between neighbours in the row (m).
        spacing_m: f64,
        /// Height of the ground below the navigator's start (m).
        below_m: f64,
        /// Slots assigned to the starts, minimising this (None: in row order).
        assign: Option<AssignBy>,
    },
    /// The listed followers at their positions (m, relative to the navigator's start, world
    /// axes); the others in their slots.
    Explicit(Vec<(UavId, [f64; 3])>),
}

impl Placement {
    /// True when every UAV starts in its slot.
    pub fn in_slots(&self) -> bool {
        matches!(self, Placement::Slots)
    }

    /// True when the simulator draws the starts at random.
    pub fn is_random(&self) -> bool {
        matches!(self, Placement::Box { .. } | Placement::Disc { .. })
    }

    /// True when the followers start at rest on the ground.
    pub fn is_take_off(&self) -> bool {
        matches!(self, Placement::Row { .. })
    }
}
