//! What a mesh is beyond a triangulation of its vertices ([`MeshKind`]): which of the
//! validator's checks hold for it. Its producer declares it, its writer records it
//! (docs/FORMATS.md), and `sweeptin check` picks its checks by it ([`super::CdtCheck::for_kind`],
//! [`super::StreamCheck::for_kind`]).

/// What a mesh is beyond a triangulation of its vertices: the properties a check must not
/// expect of it. Producers declare it ([`crate::sink::MeshSink::declare`]); writers record it (a PLY
/// `comment sweeptin: …` line, the `.stin` header's flags: docs/FORMATS.md), and
/// `sweeptin check` reads it back and checks what holds. The default, no flag, is a Delaunay
/// triangulation of its vertices whose boundary is their convex hull.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct MeshKind {
    /// Some edges are constraints (breaklines, boundary or hole rings) that the file does not
    /// list: those edges may be not locally Delaunay.
    pub constrained: bool,
    /// The boundary is not the vertices' convex hull: trimmed (a boundary, holes, `--max-edge`,
    /// missing cells of a grid), or with Steiner points on it rounded off the hull's edges.
    pub trimmed: bool,
    /// Not Delaunay by design: `--no-flat-triangles`, or tiles or windows joined along their
    /// borders.
    pub not_delaunay: bool,
}

impl MeshKind {
    /// The words written for each flag, in order.
    const WORDS: [&'static str; 3] = ["constrained", "trimmed", "not-delaunay"];
    /// The longest [`MeshKind::words`] (every flag), which a fixed-length header reserves.
    pub const MAX_WORDS: usize = 32;

    fn flags(self) -> [bool; 3] {
        [self.constrained, self.trimmed, self.not_delaunay]
    }

    fn from_flags(f: [bool; 3]) -> Self {
        MeshKind {
            constrained: f[0],
            trimmed: f[1],
            not_delaunay: f[2],
        }
    }

    /// Both kinds' flags: what neither `self` nor `other` promises.
    #[must_use]
    pub fn union(self, other: MeshKind) -> MeshKind {
        let (a, b) = (self.flags(), other.flags());
        Self::from_flags([a[0] || b[0], a[1] || b[1], a[2] || b[2]])
    }

    /// The flags as words: `delaunay` for none, else e.g. `constrained trimmed not-delaunay`.
    pub fn words(self) -> String {
        let w: Vec<&str> = Self::WORDS
            .iter()
            .zip(self.flags())
            .filter_map(|(w, f)| f.then_some(*w))
            .collect();
        if w.is_empty() {
            "delaunay".into()
        } else {
            w.join(" ")
        }
    }

    /// The kind [`MeshKind::words`] wrote, or `Err` with the first word it does not know (a
    /// later version's flag: that mesh cannot be checked as this one knows).
    ///
    /// # Errors
    /// The unknown word.
    pub fn from_words(text: &str) -> std::result::Result<MeshKind, String> {
        let mut f = [false; 3];
        for w in text.split_ascii_whitespace() {
            match Self::WORDS.iter().position(|k| *k == w) {
                Some(i) => f[i] = true,
                None if w == "delaunay" => {}
                None => return Err(w.to_string()),
            }
        }
        Ok(Self::from_flags(f))
    }

    /// The flags as the bits of the `.stin` header's flag word (bit 0 constrained, 1 trimmed,
    /// 2 not Delaunay).
    pub fn bits(self) -> u32 {
        self.flags()
            .iter()
            .enumerate()
            .map(|(i, &f)| u32::from(f) << i)
            .sum()
    }

    /// The kind of a flag word, or `Err` with the bits it does not know.
    ///
    /// # Errors
    /// The unknown bits.
    pub fn from_bits(bits: u32) -> std::result::Result<MeshKind, u32> {
        if bits >> 3 != 0 {
            return Err(bits & !7);
        }
        Ok(Self::from_flags([
            bits & 1 != 0,
            bits & 2 != 0,
            bits & 4 != 0,
        ]))
    }
}

#[cfg(test)]
mod tests {
    use super::MeshKind;

    #[test]
    fn mesh_kinds_read_back_as_written() {
        for bits in 0..8 {
            let k = MeshKind::from_bits(bits).unwrap();
            assert_eq!(k.bits(), bits);
            assert_eq!(MeshKind::from_words(&k.words()), Ok(k));
            assert!(k.words().len() <= MeshKind::MAX_WORDS);
        }
        assert_eq!(MeshKind::from_bits(9), Err(8));
        assert_eq!(
            MeshKind::from_words("trimmed sideways"),
            Err("sideways".into())
        );
        let c = MeshKind {
            constrained: true,
            ..MeshKind::default()
        };
        assert_eq!(c.union(MeshKind::default()), c);
        assert_eq!(MeshKind::default().words(), "delaunay");
    }
}
