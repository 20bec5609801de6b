//! A minimal WKT (1 and 2) reader: just enough structure to find names and authorities.

/// One `KEYWORD[arg, …]` object.
#[derive(Debug)]
pub(super) struct Node {
    pub(super) keyword: String,
    pub(super) args: Vec<Arg>,
}

/// An argument: a quoted string, a bare token (number or enum), or a nested object.
#[derive(Debug)]
pub(super) enum Arg {
    Text(String),
    Bare(String),
    Node(Node),
}

impl Node {
    pub(super) fn first_string(&self) -> Option<&str> {
        self.args.iter().find_map(|a| match a {
            Arg::Text(s) => Some(s.as_str()),
            _ => None,
        })
    }

    pub(super) fn children(&self) -> impl Iterator<Item = &Node> {
        self.args.iter().filter_map(|a| match a {
            Arg::Node(n) => Some(n),
            _ => None,
        })
    }

    /// The EPSG code of this object's own `AUTHORITY`/`ID` child.
    pub(super) fn epsg(&self) -> Option<u32> {
        self.children()
            .filter(|c| c.keyword == "AUTHORITY" || c.keyword == "ID")
            .find_map(|c| {
                let mut it = c.args.iter();
                let auth = match it.next()? {
                    Arg::Text(s) => s,
                    _ => return None,
                };
                if !auth.eq_ignore_ascii_case("EPSG") {
                    return None;
                }
                match it.next()? {
                    Arg::Text(s) | Arg::Bare(s) => s.trim().parse().ok(),
                    Arg::Node(_) => None,
                }
            })
    }
}

/// Parses the first object of `text`; `None` if it is not well-formed.
pub(super) fn parse(text: &str) -> Option<Node> {
    let chars: Vec<char> = text.chars().collect();
    let mut pos = 0;
    parse_node(&chars, &mut pos, 0)
}

const MAX_DEPTH: usize = 64;

fn skip_ws(c: &[char], pos: &mut usize) {
    while *pos < c.len() && c[*pos].is_whitespace() {
        *pos += 1;
    }
}

fn parse_node(c: &[char], pos: &mut usize, depth: usize) -> Option<Node> {
    if depth > MAX_DEPTH {
        return None;
    }
    skip_ws(c, pos);
    let start = *pos;
    while *pos < c.len() && (c[*pos].is_alphanumeric() || c[*pos] == '_') {
        *pos += 1;
    }
    let keyword: String = c[start..*pos].iter().collect::<String>().to_uppercase();
    skip_ws(c, pos);
    if keyword.is_empty() || *pos >= c.len() || !matches!(c[*pos], '[' | '(') {
        return None;
    }
    *pos += 1;
    let mut args = Vec::new();
    loop {
        skip_ws(c, pos);
        match c.get(*pos)? {
            ']' | ')' => {
                *pos += 1;
                return Some(Node { keyword, args });
            }
            ',' => *pos += 1,
            '"' => args.push(Arg::Text(parse_quoted(c, pos)?)),
            _ => args.push(parse_bare_or_node(c, pos, depth)?),
        }
    }
}

fn parse_quoted(c: &[char], pos: &mut usize) -> Option<String> {
    *pos += 1;
    let mut s = String::new();
    loop {
        let ch = *c.get(*pos)?;
        *pos += 1;
        if ch == '"' {
            if c.get(*pos) == Some(&'"') {
                s.push('"');
                *pos += 1;
            } else {
                return Some(s);
            }
        } else {
            s.push(ch);
        }
    }
}

fn parse_bare_or_node(c: &[char], pos: &mut usize, depth: usize) -> Option<Arg> {
    let start = *pos;
    while *pos < c.len() && !matches!(c[*pos], ',' | ']' | ')' | '[' | '(') {
        *pos += 1;
    }
    if matches!(c.get(*pos), Some('[' | '(')) {
        *pos = start;
        return parse_node(c, pos, depth + 1).map(Arg::Node);
    }
    let token: String = c[start..*pos].iter().collect();
    Some(Arg::Bare(token.trim().to_string()))
}
