//! Reading point files and writing meshes.
