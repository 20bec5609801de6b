//! The only `unsafe` code in sweeptin: read-only memory maps of the external sort's own spill files.
//!
//! A spill file is an anonymous temporary file (already unlinked, so no other process can open
//! it) that this process wrote completely and never writes again while it is mapped; that is what
//! makes mapping it sound. Records are plain old data (`bytemuck::Pod`), so any bytes are a valid
//! record, and the mapping is page-aligned, so the cast to records is aligned.
#![allow(unsafe_code)]

use bytemuck::Pod;
use memmap2::{Advice, Mmap, UncheckedAdvice};
use std::fs::File;
use std::marker::PhantomData;

/// A read-only mapping of a file of fixed-size records, read front to back.
#[derive(Debug)]
pub struct MappedRecords<T: Pod> {
    map: Option<Mmap>,
    len: usize,
    released: usize,
    _t: PhantomData<T>,
}

impl<T: Pod> MappedRecords<T> {
    /// Maps `file`, which must hold a whole number of `T` records and must not be written while
    /// mapped (the caller created it and finished writing it).
    ///
    /// # Errors
    /// The operating system's error if mapping fails, `InvalidData` if the length is not a
    /// multiple of the record size.
    pub fn map(file: &File) -> std::io::Result<Self> {
        let bytes = file.metadata()?.len() as usize;
        let size = std::mem::size_of::<T>();
        if !bytes.is_multiple_of(size) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "spill file is not a whole number of records",
            ));
        }
        if bytes == 0 {
            return Ok(MappedRecords {
                map: None,
                len: 0,
                released: 0,
                _t: PhantomData,
            });
        }
        // SAFETY: the file is a private, unlinked temporary file that this process has finished
        // writing; nothing modifies or truncates it while the map lives (see the module docs).
        let map = unsafe { Mmap::map(file)? };
        // Sequential reading: ask for aggressive read-ahead. Advisory only.
        let _ = map.advise(Advice::Sequential);
        Ok(MappedRecords {
            map: Some(map),
            len: bytes / size,
            released: 0,
            _t: PhantomData,
        })
    }

    /// All records.
    pub fn records(&self) -> &[T] {
        match &self.map {
            Some(m) => bytemuck::cast_slice(&m[..]),
            None => &[],
        }
    }

    /// Number of records.
    pub fn len(&self) -> usize {
        self.len
    }

    /// No records?
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Tells the kernel that records before `upto` will not be read again, so their pages can leave
    /// this process's resident set.
    pub fn release_before(&mut self, upto: usize) {
        let Some(map) = &self.map else { return };
        let page = 4096;
        let end = (upto.min(self.len) * std::mem::size_of::<T>()) / page * page;
        if end <= self.released {
            return;
        }
        // SAFETY: MADV_DONTNEED on a read-only, file-backed shared mapping only drops the pages
        // from this process; if they were read again they would be reloaded from the unchanged
        // file, so no reference into the map can observe different bytes.
        let _ = unsafe {
            map.unchecked_advise_range(
                UncheckedAdvice::DontNeed,
                self.released,
                end - self.released,
            )
        };
        self.released = end;
    }
}
