//! `[formation]`: slots (explicit or a generated shape), the frame, and dependency tables.

use std::collections::BTreeMap;

use nalgebra::Vector3;
use proxform_core::angle::deg;
use proxform_core::{DependencySet, FormationFrame, FormationSlot, UavId};

use super::values::{err, finite, positive, probability, required, uav, vec3, SpecError};
use super::MAX_UAVS;
use crate::defaults;
use crate::formation::lattice::default_levels;
use crate::formation::shapes::Shape;
use crate::spec::{FormationSpec, ShapeSpec};

/// A slot's `depends_on` table as written: UAV number → degree.
pub type ExplicitRefs = BTreeMap<String, f64>;

/// The formation as written: slots, frame, and each slot's explicit `depends_on` table.
pub struct Slots {
    /// One slot per UAV.
    pub slots: Vec<FormationSlot>,
    /// The formation frame.
    pub frame: FormationFrame,
    /// Each slot's `depends_on`, if written.
    pub explicit: Vec<Option<ExplicitRefs>>,
}

/// The formation's slots, its frame, and each slot's explicit `depends_on` table.
pub fn slots(f: &FormationSpec) -> Result<Slots, SpecError> {
    let frame = match f.frame.as_deref() {
        None | Some("world") => FormationFrame::World,
        Some("course") => FormationFrame::Course,
        Some(other) => {
            return Err(err("formation.frame", format!("unknown frame \"{other}\" (expected \"world\" or \"course\")")))
        }
    };
    let (slots, explicit) = slots_of(f)?;
    let n = slots.len();
    if n < 2 {
        return Err(err("formation", format!("needs at least 2 UAVs, found {n}")));
    }
    Ok(Slots { slots, frame, explicit })
}

type SlotsAndRefs = (Vec<FormationSlot>, Vec<Option<ExplicitRefs>>);

fn slots_of(f: &FormationSpec) -> Result<SlotsAndRefs, SpecError> {
    match (&f.shape, f.slot.is_empty()) {
        (Some(_), false) => {
            Err(err("formation", "give either [[formation.slot]] entries or a [formation.shape], not both"))
        }
        (None, true) => Err(err("formation", "needs [[formation.slot]] entries or a [formation.shape]")),
        (Some(shape), true) => {
            let slots = shape_of(shape)?.slots();
            let n = slots.len();
            Ok((slots, vec![None; n]))
        }
        (None, false) => {
            let n = f.slot.len();
            let mut slots = vec![None; n];
            let mut deps = vec![None; n];
            for (k, s) in f.slot.iter().enumerate() {
                let key = format!("formation.slot[{}]", k + 1);
                let id = required(&format!("{key}.id"), s.id)?;
                if id == 0 || id as usize > n {
                    return Err(err(
                        format!("{key}.id"),
                        format!("UAV numbers run from 1 to {n} (the number of slots), found {id}"),
                    ));
                }
                let i = id as usize - 1;
                if slots[i].is_some() {
                    return Err(err(format!("{key}.id"), format!("duplicate id {id}")));
                }
                let offset = vec3(&format!("{key}.offset_m"), required(&format!("{key}.offset_m"), s.offset_m)?)?;
                let att = match s.attitude_offset_deg {
                    Some(a) => vec3(&format!("{key}.attitude_offset_deg"), a)?.map(deg),
                    None => Vector3::zeros(),
                };
                slots[i] = Some(FormationSlot { offset_m: offset, attitude_offset_rad: att });
                deps[i] = s.depends_on.clone();
            }
            let slots = slots.into_iter().map(|s| s.unwrap_or(FormationSlot::at(0.0, 0.0, 0.0))).collect();
            Ok((slots, deps))
        }
    }
}

fn shape_of(s: &ShapeSpec) -> Result<Shape, SpecError> {
    let kind = required("formation.shape.kind", s.kind.clone())?;
    let uavs = || -> Result<usize, SpecError> {
        let n = required("formation.shape.uavs", s.uavs)? as usize;
        if !(2..=MAX_UAVS).contains(&n) {
            return Err(err("formation.shape.uavs", format!("needs 2 to {MAX_UAVS} UAVs, found {n}")));
        }
        Ok(n)
    };
    let spacing = || positive("formation.shape.spacing_m", required("formation.shape.spacing_m", s.spacing_m)?);
    let angle = || -> Result<f64, SpecError> {
        let a = finite("formation.shape.angle_deg", s.angle_deg.unwrap_or(defaults::SHAPE_ANGLE_DEG))?;
        if a <= 0.0 || a >= 90.0 {
            return Err(err("formation.shape.angle_deg", format!("must be in (0, 90), found {a}")));
        }
        Ok(deg(a))
    };
    let level = || finite("formation.shape.level_step_m", s.level_step_m.unwrap_or(0.0));
    Ok(match kind.as_str() {
        "triangle" => {
            let rows = required("formation.shape.rows", s.rows)? as usize;
            if !(2..=4000).contains(&rows) {
                return Err(err("formation.shape.rows", format!("needs 2 to 4000 rows, found {rows}")));
            }
            Shape::Triangle { rows, spacing: spacing()?, level_step: level()? }
        }
        "v" => Shape::V { uavs: uavs()?, spacing: spacing()?, angle: angle()?, level_step: level()? },
        "echelon" => {
            let left = match s.side.as_deref() {
                None | Some("right") => false,
                Some("left") => true,
                Some(o) => return Err(err("formation.shape.side", format!("unknown side \"{o}\" (expected \"left\" or \"right\")"))),
            };
            Shape::Echelon { uavs: uavs()?, spacing: spacing()?, angle: angle()?, left, level_step: level()? }
        }
        "line_abreast" => Shape::LineAbreast { uavs: uavs()?, spacing: spacing()?, level_step: level()? },
        "column" => Shape::Column { uavs: uavs()?, spacing: spacing()?, level_step: level()? },
        "diamond" => Shape::Diamond { uavs: uavs()?, spacing: spacing()? },
        "grid" => Shape::Grid { uavs: uavs()?, spacing: spacing()? },
        "circle" => Shape::Circle { uavs: uavs()?, radius: spacing()? },
        "lattice" => {
            let n = uavs()?;
            let levels = match s.levels {
                Some(0) => return Err(err("formation.shape.levels", "must be ≥ 1")),
                Some(l) => l as usize,
                None => default_levels(n),
            };
            Shape::Lattice { uavs: n, spacing: spacing()?, levels, level_step: level()? }
        }
        other => {
            return Err(err(
                "formation.shape.kind",
                format!("unknown shape \"{other}\" (expected triangle, v, echelon, line_abreast, column, diamond, grid, lattice or circle)"),
            ))
        }
    })
}

/// Every UAV's dependency table: its explicit `depends_on`, or one derived from the geometry
/// (`[formation.dependencies]`, METHOD §6 Choice).
pub fn dependencies(
    f: &FormationSpec,
    slots: &[FormationSlot],
    explicit: &[Option<ExplicitRefs>],
    navigator: UavId,
    sensing_range_m: f64,
) -> Result<Vec<DependencySet>, SpecError> {
    let n = slots.len();
    let auto = f.dependencies.clone().unwrap_or_default();
    let k = auto.k.unwrap_or(defaults::REFERENCES_PER_UAV) as usize;
    if k == 0 {
        return Err(err("formation.dependencies.k", "must be ≥ 1"));
    }
    let max_d = match auto.max_distance_m {
        Some(v) => positive("formation.dependencies.max_distance_m", v)?,
        None => sensing_range_m,
    };
    let nav_degree = match auto.navigator_degree {
        Some(v) => {
            let v = probability("formation.dependencies.navigator_degree", v)?;
            if v >= 1.0 {
                return Err(err("formation.dependencies.navigator_degree", "must be below 1"));
            }
            v
        }
        None => 0.0,
    };
    let derived = crate::formation::autodeps::derive(slots, navigator, k, max_d, nav_degree)
        .map_err(|e| err("formation.dependencies", e.to_string()))?;
    (0..n)
        .map(|i| match &explicit[i] {
            Some(refs) => {
                let key = format!("formation.slot[{}].depends_on", i + 1);
                let mut out = Vec::new();
                for (id, degree) in refs {
                    let j: u32 = id.parse().map_err(|_| err(&key, format!("\"{id}\" is not a UAV number")))?;
                    let j = uav(&key, j, n)?;
                    if j.index() == i {
                        return Err(err(&key, format!("UAV {} cannot depend on itself", i + 1)));
                    }
                    let d = finite(&key, *degree)?;
                    if d <= 0.0 {
                        return Err(err(&key, format!("degree of UAV {id} must be > 0, found {d}")));
                    }
                    out.push((j, d));
                }
                DependencySet::new(UavId(i as u32), n, out).map_err(|e| err(&key, e.to_string()))
            }
            None => Ok(derived[i].clone()),
        })
        .collect()
}
