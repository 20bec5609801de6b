//! Reading point files and writing meshes, all streaming-friendly.
//!
//! - [`atomic`]: [`AtomicFile`] (outputs appear only when complete) and the registry of temporary
//!   paths deleted on Ctrl-C ([`install_interrupt_handler`]).
//! - [`sink`]: the push-style [`MeshSink`] trait and [`create_mesh_sink`], which picks a writer:
//!   [`PlyWriter`] (binary PLY), [`ObjWriter`] (Wavefront OBJ), [`LandXmlWriter`] (LandXML 1.2).
//!   No writer holds the mesh in memory.
//! - [`xyz`]: XYZ text points, whole ([`read_xyz`]) or in chunks ([`XyzReader`]).
//! - [`ply`]: PLY mesh reader ([`read_ply`]), ASCII and binary.
//! - [`stin`]: sweeptin's streaming mesh format, written ([`StinWriter`]) and read back with
//!   bounded memory ([`StinReader`]).
//!
//! ```
//! use sweeptin::io::{create_mesh_sink, read_ply, MeshMeta};
//!
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("tin.ply");
//! let mut sink = create_mesh_sink(&path, None, &MeshMeta::default()).unwrap();
//! sink.vertex([0.0, 0.0, 1.0]).unwrap();
//! sink.vertex([1.0, 0.0, 2.0]).unwrap();
//! sink.vertex([0.0, 1.0, 3.0]).unwrap();
//! sink.triangle([0, 1, 2]).unwrap();
//! let summary = sink.finish().unwrap();
//! assert_eq!((summary.vertices, summary.triangles), (3, 1));
//!
//! let (vertices, triangles) = read_ply(&path).unwrap();
//! assert_eq!(vertices[2], [0.0, 1.0, 3.0]);
//! assert_eq!(triangles, vec![[0, 1, 2]]);
//! ```

pub mod atomic;
pub mod idmap;
pub mod landxml;
pub mod obj;
pub mod ply;
pub mod ply_write;
pub mod sink;
pub mod stin;
pub mod xyz;

pub use atomic::{AtomicFile, RegisteredTempDir, install_interrupt_handler};
pub use landxml::LandXmlWriter;
pub use obj::ObjWriter;
pub use ply::read_ply;
pub use ply_write::PlyWriter;
pub use sink::{MeshFormat, MeshMeta, MeshSink, MeshSummary, create_mesh_sink};
pub use stin::{StinEvent, StinReader, StinWriter};
pub use xyz::{XyzReader, read_xyz};
