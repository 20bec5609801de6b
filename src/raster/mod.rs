//! Raster grids: the grid geometry ([`grid::GridSpec`]) and writers (float32 GeoTIFF, ESRI ASCII).

pub mod ascii_write;
pub mod geotiff_write;
pub mod grid;
