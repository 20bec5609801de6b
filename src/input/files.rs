//! The input files of a command: file lists (`@list.txt`), globs expanded by the tool (a quoted
//! `'tiles/*.laz'`, as shells on Windows and batch schedulers pass it), and `.vpc` virtual point
//! clouds.
//!
//! - `@FILE` reads one path per line (blank lines and lines starting with `#` are skipped);
//!   relative paths are relative to the list's folder, as in LAStools' `-lof` lists.
//! - A path that does not exist and holds `*`, `?` or `[` is a glob pattern: its matches, sorted
//!   by name; no match is an error naming the pattern.
//! - A `.vpc` stays one input for the LAS/LAZ reader (which learns the files and their extents
//!   from it without opening them), or is replaced by its files ([`Expand::VpcFiles`]) for
//!   callers that need each file's header (plans).
//!
//! - A URL (`https://…`, `http://…`, `s3://bucket/key`) is one remote file, never a pattern; a
//!   list may name URLs, and a remote list's relative lines are URLs beside it.
//!
//! The lists and `.vpc` files read on the way are inputs too ([`Expansion::lists`]): an output
//! never replaces one (`tin @list.txt -o list.txt` overwrote the list).

use crate::error::{Error, Result};
use crate::input::las::vpc;
use crate::input::source;
use std::path::{Path, PathBuf};

/// What to do with `.vpc` inputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expand {
    /// Keep them as they are.
    KeepVpc,
    /// Replace each by the files it lists.
    VpcFiles,
}

/// The files some arguments stand for ([`expand`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Expansion {
    /// The files, in order.
    pub files: Vec<PathBuf>,
    /// The file lists (`@list.txt`, nested ones too) and the `.vpc` files replaced by their
    /// files, read to find [`Expansion::files`]: inputs of the run as much as those, which no
    /// output may replace (a `.vpc` kept as it is is among the files).
    pub lists: Vec<PathBuf>,
}

/// How a plan names an input so that its tasks find it from anywhere: a local file by its
/// absolute path (links resolved), a URL as given.
///
/// # Errors
/// [`Error::Io`] naming a local file that cannot be resolved.
pub fn absolute(p: &Path) -> Result<PathBuf> {
    if source::is_remote(p) {
        return Ok(p.to_path_buf());
    }
    std::fs::canonicalize(p).map_err(|e| Error::io(p, e))
}

/// The files `args` stand for, in order, and the lists read to find them.
///
/// # Errors
/// [`Error::Io`] when a list cannot be read; [`Error::Options`] for a glob that matches nothing
/// or is not a valid pattern, or an empty list; the `.vpc` reader's errors.
pub fn expand(args: &[PathBuf], vpc_mode: Expand) -> Result<Expansion> {
    let mut out = Expansion::default();
    for a in args {
        expand_one(a, vpc_mode, &mut out, 0)?;
    }
    Ok(out)
}

fn expand_one(a: &Path, vpc_mode: Expand, out: &mut Expansion, depth: usize) -> Result<()> {
    let text = a.to_string_lossy();
    if let Some(list) = text.strip_prefix('@') {
        if depth > 8 {
            return Err(Error::Options(format!(
                "{text}: file lists nest more than 8 deep (a list that names itself?)"
            )));
        }
        let list = Path::new(list);
        let body = source::read_to_string(list)?;
        out.lists.push(list.to_path_buf());
        let dir = list.parent().unwrap_or(Path::new(""));
        let before = out.files.len();
        for line in body.lines() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let p = Path::new(line);
            let p = if p.is_absolute() || line.starts_with('@') || source::is_remote(p) {
                p.to_path_buf()
            } else {
                source::beside(dir, line)
            };
            expand_one(&p, vpc_mode, out, depth + 1)?;
        }
        if out.files.len() == before {
            return Err(Error::Options(format!(
                "{}: the file list names no file",
                list.display()
            )));
        }
        return Ok(());
    }
    // A URL is one object: `?` starts its query, and a server cannot be listed.
    if !source::is_remote(a) && !a.exists() && text.contains(['*', '?', '[']) {
        let paths = glob::glob(&text)
            .map_err(|e| Error::Options(format!("{text}: not a valid pattern: {e}")))?;
        let mut found: Vec<PathBuf> = paths.filter_map(std::result::Result::ok).collect();
        found.sort();
        if found.is_empty() {
            return Err(Error::Options(format!(
                "{text}: no file matches the pattern"
            )));
        }
        for p in found {
            push(p, vpc_mode, out)?;
        }
        return Ok(());
    }
    push(a.to_path_buf(), vpc_mode, out)
}

fn push(p: PathBuf, vpc_mode: Expand, out: &mut Expansion) -> Result<()> {
    if vpc_mode == Expand::VpcFiles && vpc::is_vpc(&p) {
        out.files.extend(vpc::read(&p)?.into_iter().map(|e| e.path));
        out.lists.push(p);
    } else {
        out.files.push(p);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_and_globs() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        for n in ["b.laz", "a.laz", "c.las"] {
            std::fs::write(d.join(n), "").unwrap();
        }
        std::fs::create_dir(d.join("sub")).unwrap();
        std::fs::write(d.join("sub/list.txt"), "# tiles\n../c.las\n\n../a.laz\n").unwrap();
        let pattern = d.join("*.laz");
        let got = expand(std::slice::from_ref(&pattern), Expand::KeepVpc).unwrap();
        assert_eq!(got.files, [d.join("a.laz"), d.join("b.laz")]);
        assert!(got.lists.is_empty());
        let list = PathBuf::from(format!("@{}", d.join("sub/list.txt").display()));
        let got = expand(&[list, d.join("b.laz")], Expand::KeepVpc).unwrap();
        assert_eq!(got.lists, [d.join("sub/list.txt")]);
        assert_eq!(
            got.files,
            [
                d.join("sub/../c.las"),
                d.join("sub/../a.laz"),
                d.join("b.laz")
            ]
        );
        let e = expand(&[d.join("*.xyz")], Expand::KeepVpc).unwrap_err();
        assert!(e.to_string().contains("no file matches"), "{e}");
        let e = expand(&[PathBuf::from("@/no/such/list.txt")], Expand::KeepVpc).unwrap_err();
        assert!(e.to_string().contains("/no/such/list.txt"), "{e}");
        // A file that exists is taken as it is, brackets and all.
        std::fs::write(d.join("x[1].laz"), "").unwrap();
        let got = expand(&[d.join("x[1].laz")], Expand::KeepVpc).unwrap();
        assert_eq!(got.files, [d.join("x[1].laz")]);
    }
}
