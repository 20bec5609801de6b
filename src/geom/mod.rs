//! Geometry every stage shares: the exact predicates (the only place orientation and in-circle
//! decisions are made), exact arithmetic tests, a uniform grid index for segments and points, and
//! the crate's one small random generator.

pub(crate) mod exact;
pub(crate) mod grid;
pub mod predicates;
pub(crate) mod rng;
