//! Geometry every stage shares: the exact predicates (the only place orientation and in-circle
//! decisions are made), exact arithmetic tests, and a uniform grid index for segments and points.

pub(crate) mod exact;
pub(crate) mod grid;
pub mod predicates;
