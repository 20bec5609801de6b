//! A local file as a [`super::Object`]: positioned reads, no shared cursor.

use std::fs::File;
use std::io;
use std::path::Path;

/// A local file, its size and modification time as opened.
pub(super) struct Local {
    file: File,
    len: u64,
    modified: Option<std::time::SystemTime>,
}

impl Local {
    pub(super) fn open(path: &Path) -> io::Result<Local> {
        let file = File::open(path)?;
        let m = file.metadata()?;
        Ok(Local {
            len: m.len(),
            modified: m.modified().ok(),
            file,
        })
    }
}

impl super::Object for Local {
    fn len(&self) -> u64 {
        self.len
    }

    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        read_file_at(&self.file, offset, buf)
    }

    fn identity(&self) -> String {
        let secs = self
            .modified
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0.0, |d| d.as_secs_f64());
        format!("{} bytes, modified at {secs:.3} s", self.len)
    }
}

/// Fills `buf` with the bytes of `file` at `offset`, without moving a shared cursor.
#[cfg(unix)]
pub(super) fn read_file_at(file: &File, offset: u64, buf: &mut [u8]) -> io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
}

/// Fills `buf` with the bytes of `file` at `offset`.
#[cfg(not(unix))]
pub(super) fn read_file_at(file: &File, offset: u64, buf: &mut [u8]) -> io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let mut f = file;
    f.seek(SeekFrom::Start(offset))?;
    f.read_exact(buf)
}
