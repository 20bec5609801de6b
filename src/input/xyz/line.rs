//! One line of XYZ text: its fields, their separators and numbers, under the rules of the
//! [module docs](super); shared with the query positions of `sample`
//! ([`crate::products::sample`]).

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
    let axis = |n: &str| match n {
        "x" | "easting" | "east" | "lon" | "long" | "longitude" => Some(0),
        "y" | "northing" | "north" | "lat" | "latitude" => Some(1),
        "z" | "elevation" | "elev" | "height" | "alt" | "altitude" => Some(2),
        _ => None,
    };
    for (i, n) in names.iter().enumerate() {
        if let Some(a) = axis(n)
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
