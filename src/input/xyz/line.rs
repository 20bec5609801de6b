//! One line of XYZ text: its fields, their separators and numbers, under the rules of the
//! [module docs](super); shared with the query positions of `sample`
//! ([`crate::products::sample`]), which also reads x and y from the columns a header names
//! ([`parse_columns`]).

/// What is wrong with a line.
#[derive(Debug, PartialEq)]
pub(crate) enum LineError {
    /// Fewer fields than wanted (`wanted`: 3 for points, 2 for query positions).
    TooFew {
        found: usize,
        wanted: usize,
    },
    EmptyField {
        field: usize,
    },
    MixedSeparators,
    CommaAndBlank,
    /// A `\r` with more of the line after it: lines ended by CR alone.
    CarriageReturn,
    NotANumber {
        field: usize,
        token: String,
    },
    NonFinite {
        field: usize,
        token: String,
    },
    /// A line without the column its header names for x (`field` 0) or y (1).
    NoColumn {
        field: usize,
        column: usize,
        found: usize,
    },
}

impl std::fmt::Display for LineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const NAMES: [&str; 3] = ["x", "y", "z"];
        match self {
            LineError::TooFew { found, wanted } => write!(
                f,
                "expected {wanted} numbers ({}), found {found} field{}",
                NAMES[..*wanted].join(" "),
                if *found == 1 { "" } else { "s" }
            ),
            LineError::EmptyField { field } => write!(
                f,
                "{} is an empty field (two separators in a row): a missing value is never \
                 read as the next column's",
                NAMES[*field]
            ),
            LineError::MixedSeparators => write!(
                f,
                "the line mixes ',' and ';' as separators (decimal commas? write numbers with \
                 a decimal point)"
            ),
            LineError::CommaAndBlank => write!(
                f,
                "the line separates x, y and z by ',' or ';' in one place and by blanks in \
                 another (decimal commas? write numbers with a decimal point)"
            ),
            LineError::CarriageReturn => f.write_str(CR_ONLY),
            LineError::NotANumber { field, token } => {
                write!(f, "{} is not a number: \"{token}\"", NAMES[*field])
            }
            LineError::NonFinite { field, token } => {
                write!(f, "{} is not a finite number: \"{token}\"", NAMES[*field])
            }
            LineError::NoColumn {
                field,
                column,
                found,
            } => write!(
                f,
                "{} is read from column {} (as the header names it), but the line has {found} \
                 field{}",
                NAMES[*field],
                column + 1,
                if *found == 1 { "" } else { "s" }
            ),
        }
    }
}

/// Why a line with a carriage return inside is refused.
pub(super) const CR_ONLY: &str = "a carriage return (\\r) inside the line: the file seems to end its lines \
                       with \\r alone (classic Mac OS), which reads as one line; convert it \
                       first, e.g. tr '\\r' '\\n' < IN > OUT";

/// Refuses a header that names x, y or z in another column than the one they are read from
/// (`id,x,y,z` was read as x = id, y = x, z = y; `z y x` swapped x and z). Names it does not
/// know are left alone.
pub(super) fn check_header(bytes: &[u8]) -> std::result::Result<(), String> {
    if bytes.trim_ascii_end().contains(&b'\r') {
        return Err(CR_ONLY.to_string());
    }
    let text = String::from_utf8_lossy(bytes);
    let names: Vec<String> = text
        .split([',', ';', '\t', ' ', '\r'])
        .filter(|s| !s.is_empty())
        .map(|s| s.trim_matches(['"', '\'']).to_ascii_lowercase())
        .collect();
    for (i, n) in names.iter().enumerate() {
        if let Some(a) = axis_of(n)
            && a != i
        {
            return Err(format!(
                "the header names column {} \"{n}\", but the columns are read as x, y, z in \
                 this order (the header is {}): put x, y and z first",
                i + 1,
                names.join(", ")
            ));
        }
    }
    Ok(())
}

/// The axis a header's column name stands for (0 x, 1 y, 2 z; lower case, unquoted), as
/// PDAL's and GDAL's readers take them: `x`, `easting`, `lon`…; `None` for other names.
fn axis_of(name: &str) -> Option<usize> {
    match name {
        "x" | "easting" | "east" | "lon" | "long" | "longitude" => Some(0),
        "y" | "northing" | "north" | "lat" | "latitude" => Some(1),
        "z" | "elevation" | "elev" | "height" | "alt" | "altitude" => Some(2),
        _ => None,
    }
}

/// The columns a header line names for x and y (by name whatever the case: `x`, `easting`,
/// `lon`…, as PDAL's and GDAL's readers take them; split as [`parse_columns`] splits the data
/// lines), and whether it has a column named `z`. A header that names neither, or one of them
/// twice, is refused: read by position, `id,x,y` gave `sample` x = id and y = x, every query
/// outside the TIN.
pub(crate) fn header_axes(bytes: &[u8]) -> std::result::Result<([usize; 2], bool), String> {
    let names = header_columns(bytes).map_err(|e| e.to_string())?;
    let shown = names.join(", ");
    let find = |axis: usize| -> std::result::Result<Option<usize>, String> {
        let mut at = (0..names.len()).filter(|&i| axis_of(&names[i]) == Some(axis));
        match (at.next(), at.next()) {
            (Some(i), Some(j)) => Err(format!(
                "the header names {} twice, in columns {} and {} (the header is {shown}): \
                 name one column only",
                ["x", "y"][axis],
                i + 1,
                j + 1
            )),
            (i, _) => Ok(i),
        }
    };
    match (find(0)?, find(1)?) {
        (Some(x), Some(y)) => Ok(([x, y], names.iter().any(|n| n == "z"))),
        _ => Err(format!(
            "the header does not name the x and y columns (it is {shown}): name them x and y \
             (or easting and northing), or remove the header to read x and y from the first \
             two columns"
        )),
    }
}

/// The column names of a header line split as [`parse_columns`] splits its data lines, in lower
/// case, without their quotes.
fn header_columns(bytes: &[u8]) -> std::result::Result<Vec<String>, LineError> {
    let line = bytes.trim_ascii();
    if line.contains(&b'\r') {
        return Err(LineError::CarriageReturn);
    }
    Ok(split_columns(line)?
        .into_iter()
        .map(|f| {
            String::from_utf8_lossy(f.trim_ascii())
                .trim_matches(['"', '\''])
                .to_ascii_lowercase()
        })
        .collect())
}

/// The numbers in columns `cols` (0-based; the first is read as x, the second as y) of a line
/// whose header names its columns (`sample`'s queries under `id,x,y`): the fields split by the
/// line's comma or semicolon, where an empty field is a column of its own as in CSV and a
/// double-quoted field may hold the separator, or by runs of blanks when it has neither.
/// `None` for blank and comment lines. Decimal commas are refused as [`parse_fields`] refuses
/// them (both `,` and `;`, or blanks inside a field read as a number), and so is an empty field
/// read as a number.
pub(crate) fn parse_columns(
    bytes: &[u8],
    cols: [usize; 2],
) -> std::result::Result<Option<[f64; 2]>, LineError> {
    let line = bytes.trim_ascii();
    if line.contains(&b'\r') {
        return Err(LineError::CarriageReturn);
    }
    if line.is_empty() || line[0] == b'#' {
        return Ok(None);
    }
    let fields = split_columns(line)?;
    let mut p = [0.0; 2];
    for (field, (&c, value)) in cols.iter().zip(p.iter_mut()).enumerate() {
        let token = fields
            .get(c)
            .ok_or(LineError::NoColumn {
                field,
                column: c,
                found: fields.len(),
            })?
            .trim_ascii();
        if token.is_empty() {
            return Err(LineError::EmptyField { field });
        }
        if token.iter().any(|b| is_separator(*b)) {
            return Err(LineError::CommaAndBlank);
        }
        *value = parse_number(token, field)?;
    }
    Ok(Some(p))
}

/// The fields of `line` (trimmed, not empty): split by its comma or semicolon outside double
/// quotes, or by runs of blanks when it has neither.
fn split_columns(line: &[u8]) -> std::result::Result<Vec<&[u8]>, LineError> {
    let mut hard = 0u8;
    let mut quoted = false;
    for &b in line {
        match b {
            b'"' => quoted = !quoted,
            b',' | b';' if !quoted => {
                if hard != 0 && b != hard {
                    return Err(LineError::MixedSeparators);
                }
                hard = b;
            }
            _ => {}
        }
    }
    if hard == 0 {
        return Ok(line
            .split(|b| is_separator(*b))
            .filter(|f| !f.is_empty())
            .collect());
    }
    let mut fields = Vec::new();
    let (mut start, mut quoted) = (0, false);
    for (i, &b) in line.iter().enumerate() {
        if b == b'"' {
            quoted = !quoted;
        } else if b == hard && !quoted {
            fields.push(&line[start..i]);
            start = i + 1;
        }
    }
    fields.push(&line[start..]);
    Ok(fields)
}

#[inline]
fn is_separator(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b',' | b';' | b'\r')
}

/// Parses one line (without its `\n`): `None` for blank and comment lines.
#[inline]
pub(super) fn parse_line(bytes: &[u8]) -> std::result::Result<Option<[f64; 3]>, LineError> {
    parse_fields::<3>(bytes)
}

/// Parses the first `N` numbers of a line (without its `\n`) under the separator rules of the
/// module docs: `None` for blank and comment lines. `N` is 3 for points, 2 for the query
/// positions of `sample` (one home for both: those read `1,5;3,5` as (1, 5)).
#[inline]
pub(crate) fn parse_fields<const N: usize>(
    bytes: &[u8],
) -> std::result::Result<Option<[f64; N]>, LineError> {
    let mut pos = 0;
    let mut p = [0.0; N];
    // The line's comma or semicolon: a run of white space counts as one separator, but two of
    // these in a run leave an empty field, and both in one line are decimal commas.
    let mut hard = 0u8;
    // Whether the separator before y was a comma or semicolon: the one before z must agree
    // (`0,15\t0,29\t10,00` read as 0, 15, 0).
    let mut first_hard = None;
    for (field, value) in p.iter_mut().enumerate() {
        let hards = skip_separators(bytes, &mut pos, &mut hard)?;
        if hards > usize::from(field > 0) && pos < bytes.len() {
            return Err(LineError::EmptyField { field });
        }
        if field > 0 && pos < bytes.len() && bytes[pos] != b'#' {
            match first_hard {
                None => first_hard = Some(hards > 0),
                Some(h) if h != (hards > 0) => return Err(LineError::CommaAndBlank),
                Some(_) => {}
            }
        }
        if pos == bytes.len() {
            return if field == 0 {
                Ok(None)
            } else {
                Err(LineError::TooFew {
                    found: field,
                    wanted: N,
                })
            };
        }
        if field == 0 && bytes[pos] == b'#' {
            // A comment ends at the line's end: with lines ended by `\r` alone, the whole file.
            if bytes.trim_ascii_end().contains(&b'\r') {
                return Err(LineError::CarriageReturn);
            }
            return Ok(None);
        }
        let from = pos;
        let (end, fast) = scan_field(bytes, pos);
        pos = end;
        *value = match fast {
            Some(v) => v,
            None => parse_number(&bytes[from..end], field)?,
        };
    }
    // The separator after z, when a column follows, is of the same kind too: a decimal comma in
    // z alone (`480000\t6200000\t12,75`, `480000;6200000;12,75`) was read as z = 12.
    let hards = skip_separators(bytes, &mut pos, &mut hard)?;
    if pos < bytes.len() {
        if bytes[pos] != b'#' && first_hard != Some(hards > 0) {
            return Err(LineError::CommaAndBlank);
        }
        // Extra columns or a comment run to the line's end: with lines ended by `\r` alone, to
        // the file's end (`0 0 1 5\r1 0 2 6\r…` was one point).
        if memchr::memchr(b'\r', bytes[pos..].trim_ascii_end()).is_some() {
            return Err(LineError::CarriageReturn);
        }
    }
    Ok(Some(p))
}

/// Moves `pos` past a run of separators and returns how many commas or semicolons it held;
/// `hard` is the line's comma or semicolon (the first seen), and the other one is
/// [`LineError::MixedSeparators`].
#[inline]
fn skip_separators(
    bytes: &[u8],
    pos: &mut usize,
    hard: &mut u8,
) -> std::result::Result<usize, LineError> {
    let mut hards = 0;
    let mut cr = false;
    while *pos < bytes.len() && is_separator(bytes[*pos]) {
        let b = bytes[*pos];
        cr |= b == b'\r';
        if b == b',' || b == b';' {
            if *hard != 0 && b != *hard {
                return Err(LineError::MixedSeparators);
            }
            *hard = b;
            hards += 1;
        }
        *pos += 1;
    }
    if cr && *pos < bytes.len() {
        return Err(LineError::CarriageReturn);
    }
    Ok(hards)
}

/// Finds the end of the field starting at `pos` and, in the same pass, computes its value when
/// it is a plain decimal that [`fast_decimal`]'s exact fast path covers.
#[inline]
fn scan_field(bytes: &[u8], mut pos: usize) -> (usize, Option<f64>) {
    let negative = bytes[pos] == b'-';
    if negative || bytes[pos] == b'+' {
        pos += 1;
    }
    let mut mantissa: u64 = 0;
    let mut count = 0u32;
    let mut point = usize::MAX;
    let mut plain = true;
    while pos < bytes.len() {
        let b = bytes[pos];
        let digit = b.wrapping_sub(b'0');
        if digit < 10 {
            mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(digit));
            count += 1;
        } else if b == b'.' && point == usize::MAX {
            point = pos + 1;
        } else if is_separator(b) {
            break;
        } else {
            plain = false;
        }
        pos += 1;
    }
    let scale = if point == usize::MAX { 0 } else { pos - point };
    if !plain || count == 0 || count > 19 || mantissa >= 1 << 53 || scale >= POW10.len() {
        return (pos, None);
    }
    let value = mantissa as f64 / POW10[scale];
    (pos, Some(if negative { -value } else { value }))
}

/// Parses a field that the fast path did not cover: `str::parse`, then the finiteness check.
fn parse_number(token: &[u8], field: usize) -> std::result::Result<f64, LineError> {
    let text = || {
        let s = String::from_utf8_lossy(token);
        if s.chars().count() > 40 {
            s.chars().take(40).chain("…".chars()).collect()
        } else {
            s.into_owned()
        }
    };
    let value = fast_decimal(token)
        .or_else(|| std::str::from_utf8(token).ok()?.parse::<f64>().ok())
        .ok_or_else(|| LineError::NotANumber {
            field,
            token: text(),
        })?;
    if !value.is_finite() {
        return Err(LineError::NonFinite {
            field,
            token: text(),
        });
    }
    Ok(value)
}

/// Exact powers of ten representable in `f64`.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Clinger's fast path for plain decimals (`[+-]digits[.digits]`, no exponent): when the digits
/// form an integer `m < 2^53` and there are at most 22 of them after the point, both `m` and
/// `10^k` are exact in `f64` and one IEEE division gives the correctly rounded value, the same
/// bits `str::parse` gives. Anything else returns `None` and goes to `str::parse`.
#[inline]
fn fast_decimal(token: &[u8]) -> Option<f64> {
    let (negative, digits) = match token.first()? {
        b'-' => (true, &token[1..]),
        b'+' => (false, &token[1..]),
        _ => (false, token),
    };
    let mut mantissa: u64 = 0;
    let mut count = 0usize;
    let mut fraction: Option<usize> = None;
    for (i, &b) in digits.iter().enumerate() {
        match b {
            b'0'..=b'9' => {
                if count >= 19 {
                    return None;
                }
                mantissa = mantissa * 10 + u64::from(b - b'0');
                count += 1;
            }
            b'.' if fraction.is_none() => fraction = Some(i + 1),
            _ => return None,
        }
    }
    if count == 0 || mantissa >= 1 << 53 {
        return None;
    }
    let scale = fraction.map_or(0, |f| digits.len() - f);
    let value = mantissa as f64 / *POW10.get(scale)?;
    Some(if negative { -value } else { value })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_path_matches_std_parse() {
        let mut r = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            r
        };
        let mut tokens: Vec<String> = [
            "0",
            "-0",
            "+0",
            "0.",
            ".0",
            "5.",
            ".5",
            "-.5",
            "1.",
            "00012.5000",
            "9007199254740991",
            "9007199254740992",
            "9007199254740993",
            "0.1",
            "0.30000000000000004",
            "1234567890123456789",
            "12345678901234567890",
            "1.0000000000000000000001",
            "0.0000000000000000000001",
            "0.00000000000000000000001",
            "511176.115",
            "-122746.065",
            "1e3",
            ".",
            "-",
            "+",
            "",
            "1.2.3",
            "1-2",
            "--1",
            "0x10",
            "1_0",
            "١",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        for _ in 0..20_000 {
            let int = next() % 10_000_000;
            let frac = next() % 1_000_000;
            let width = (next() % 9) as usize;
            let sign = ["", "-", "+"][(next() % 3) as usize];
            tokens.push(format!("{sign}{int}.{frac:0width$}"));
            tokens.push(format!("{}", f64::from_bits(next() >> 2)));
        }
        for t in &tokens {
            let fast = fast_decimal(t.as_bytes());
            let std = t.parse::<f64>().ok();
            if let Some(v) = fast {
                assert_eq!(Some(v.to_bits()), std.map(f64::to_bits), "{t:?}");
            }
            let full = parse_number(t.as_bytes(), 0).ok();
            let want = std.filter(|v| v.is_finite());
            assert_eq!(full.map(f64::to_bits), want.map(f64::to_bits), "{t:?}");
            if !t.is_empty() {
                let want = want.map(|v| [v.to_bits(), 0, v.to_bits()]);
                for line in [format!("{t},0 ,{t}, {t}\r"), format!("{t} 0\t{t} {t}\r")] {
                    let got = parse_line(line.as_bytes()).ok().flatten();
                    assert_eq!(got.map(|p| p.map(f64::to_bits)), want, "{line:?}");
                }
            }
        }
    }
}
