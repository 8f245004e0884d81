//! Errors raised when controller, formation or vehicle parameters are out of their domain.

/// A parameter outside its allowed domain. `field` names the parameter as documented.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// A numeric parameter is outside its range (or not finite).
    #[error("{field} = {value} is invalid: expected {expected}")]
    OutOfRange {
        /// The parameter's name.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// What was expected.
        expected: &'static str,
    },
    /// A dependency table names a UAV that is not in the formation, or the UAV itself.
    #[error("dependency table of {owner} names {reference}: {reason}")]
    BadReference {
        /// The UAV whose table is wrong.
        owner: crate::UavId,
        /// The UAV it names.
        reference: crate::UavId,
        /// What is wrong.
        reason: &'static str,
    },
    /// A UAV id outside the formation.
    #[error("{id} is not in the formation of {size} UAVs")]
    UnknownUav {
        /// The id.
        id: crate::UavId,
        /// Formation size.
        size: usize,
    },
}

/// Checks that `value` is finite and strictly positive.
pub fn positive(field: &'static str, value: f64) -> Result<(), ConfigError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ConfigError::OutOfRange { field, value, expected: "a finite value > 0" })
    }
}

/// Checks that `value` lies in `[0, 1]`.
pub fn unit_interval(field: &'static str, value: f64) -> Result<(), ConfigError> {
    if (0.0..=1.0).contains(&value) {
        Ok(())
    } else {
        Err(ConfigError::OutOfRange { field, value, expected: "a value in [0, 1]" })
    }
}
