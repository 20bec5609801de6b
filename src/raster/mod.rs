//! Raster grids: the grid geometry ([`grid::GridSpec`]), writers (float32 GeoTIFF, ESRI ASCII)
//! and the reader ([`read::RasterReader`]).

pub mod ascii_write;
pub mod geotiff_write;
pub mod grid;
pub mod read;
