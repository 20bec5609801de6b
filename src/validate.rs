//! Independent validation of a triangulation.

use crate::error::Result;

/// Placeholder: validates a triangulation.
pub fn validate(_vertices: &[[f64; 3]], _triangles: &[[u32; 3]]) -> Result<()> {
    Ok(())
}
