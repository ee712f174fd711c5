//! A TOML document as a tree of values that remember where they came from,
//! so that every error — the shell's own or a plugin's, by key path — names
//! the file, line and column.

use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use std::ops::Range;
use toml::Spanned;

/// Where a value came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Origin {
    /// A byte range of the scene file.
    File(Range<usize>),
    /// A `--set key=value` on the command line.
    CommandLine(String),
    /// The file as a whole (it could not be read, say).
    Whole,
    /// A byte range of a file the scene includes (`include`).
    Included(std::sync::Arc<crate::error::FileText>, Range<usize>),
}

impl Node {
    /// An empty table with no origin of its own.
    pub(crate) fn empty_table() -> Node {
        Node {
            origin: Origin::Whole,
            value: Val::Table(Vec::new()),
        }
    }

    /// Mark every origin in this tree (keys included) as a range of the
    /// included file `file`.
    pub(crate) fn into_included(mut self, file: &std::sync::Arc<crate::error::FileText>) -> Node {
        fn walk(n: &mut Node, f: &std::sync::Arc<crate::error::FileText>) {
            if let Origin::File(r) = &n.origin {
                n.origin = Origin::Included(f.clone(), r.clone());
            }
            match &mut n.value {
                Val::Arr(a) => a.iter_mut().for_each(|c| walk(c, f)),
                Val::Table(t) => {
                    for (_, o, c) in t.iter_mut() {
                        if let Origin::File(r) = o {
                            *o = Origin::Included(f.clone(), r.clone());
                        }
                        walk(c, f);
                    }
                }
                _ => {}
            }
        }
        walk(&mut self, file);
        self
    }
}

/// A value with its origin.
#[derive(Debug, Clone)]
pub struct Node {
    /// Where it came from.
    pub origin: Origin,
    /// The value.
    pub value: Val,
}

/// TOML values. Tables keep their keys' order and the keys' own origins.
#[derive(Debug, Clone)]
pub enum Val {
    /// A string.
    Str(String),
    /// An integer.
    Int(i64),
    /// A float (possibly `nan` or `inf`: rejected where numbers are used).
    Float(f64),
    /// A boolean.
    Bool(bool),
    /// A date-time (not used by rtk; rejected where it appears).
    Datetime,
    /// An array.
    Arr(Vec<Node>),
    /// A table: (key, key origin, value).
    Table(Vec<(String, Origin, Node)>),
}

impl Val {
    /// Human name of the type, for messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            Val::Str(_) => "a string",
            Val::Int(_) => "an integer",
            Val::Float(_) => "a float",
            Val::Bool(_) => "a boolean",
            Val::Datetime => "a date-time",
            Val::Arr(_) => "an array",
            Val::Table(_) => "a table",
        }
    }
}

impl Node {
    /// Look up a key of a table.
    pub fn get(&self, key: &str) -> Option<&Node> {
        match &self.value {
            Val::Table(t) => t.iter().find(|(k, _, _)| k == key).map(|(_, _, v)| v),
            _ => None,
        }
    }

    /// The origin of a key of a table (the key itself, for "unknown key" errors).
    pub fn key_origin(&self, key: &str) -> Option<&Origin> {
        match &self.value {
            Val::Table(t) => t.iter().find(|(k, _, _)| k == key).map(|(_, o, _)| o),
            _ => None,
        }
    }

    /// Follow a key path such as `center[1]` or `a.b[0].c`; returns the deepest
    /// node reached (the error is at or inside it).
    pub fn locate(&self, path: &str) -> &Node {
        let mut cur = self;
        for seg in split_path(path) {
            let next = match (&cur.value, seg) {
                (Val::Table(_), Seg::Key(k)) => cur.get(k),
                (Val::Arr(a), Seg::Index(i)) => a.get(i),
                _ => None,
            };
            match next {
                Some(n) => cur = n,
                None => break,
            }
        }
        cur
    }

    /// The origin of the key path's last key when it exists as a key, else the
    /// deepest node's origin (so "unknown key" points at the key).
    pub fn locate_origin(&self, path: &str) -> Origin {
        let segs: Vec<Seg> = split_path(path).collect();
        if let Some((Seg::Key(last), init)) = segs.split_last() {
            let parent_path = join_path(init);
            let parent = self.locate(&parent_path);
            if let Some(o) = parent.key_origin(last) {
                return o.clone();
            }
        }
        self.locate(path).origin.clone()
    }

    /// Set `path` (dotted keys) to `value`, creating tables on the way.
    pub fn set_path(&mut self, keys: &[&str], value: Node) -> Result<(), String> {
        let Some((first, rest)) = keys.split_first() else {
            *self = value;
            return Ok(());
        };
        let origin = value.origin.clone();
        let Val::Table(t) = &mut self.value else {
            return Err(format!(
                "`{first}` is inside {}, not a table",
                self.value.type_name()
            ));
        };
        if let Some(pos) = t.iter().position(|(k, _, _)| k == first) {
            return t[pos].2.set_path(rest, value);
        }
        let mut child = Node {
            origin: origin.clone(),
            value: Val::Table(Vec::new()),
        };
        child.set_path(rest, value)?;
        t.push((first.to_string(), origin, child));
        Ok(())
    }
}

enum Seg<'a> {
    Key(&'a str),
    Index(usize),
}

fn split_path(path: &str) -> impl Iterator<Item = Seg<'_>> {
    path.split('.').filter(|s| !s.is_empty()).flat_map(|part| {
        let mut out = Vec::new();
        let (key, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if !key.is_empty() {
            out.push(Seg::Key(key));
        }
        while let Some(end) = rest.find(']') {
            if let Ok(i) = rest[1..end].parse() {
                out.push(Seg::Index(i));
            }
            rest = &rest[end + 1..];
        }
        out
    })
}

fn join_path(segs: &[Seg]) -> String {
    let mut s = String::new();
    for seg in segs {
        match seg {
            Seg::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Seg::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

impl<'de> Deserialize<'de> for Node {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s: Spanned<Val> = Spanned::deserialize(d)?;
        Ok(Node {
            origin: Origin::File(s.span()),
            value: s.into_inner(),
        })
    }
}

impl<'de> Deserialize<'de> for Val {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ValVisitor)
    }
}

struct ValVisitor;

impl<'de> Visitor<'de> for ValVisitor {
    type Value = Val;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a TOML value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Val, E> {
        Ok(Val::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Val, E> {
        Ok(Val::Int(v))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Val, E> {
        i64::try_from(v).map(Val::Int).map_err(|_| out_of_range(v))
    }
    fn visit_i128<E: de::Error>(self, v: i128) -> Result<Val, E> {
        i64::try_from(v).map(Val::Int).map_err(|_| out_of_range(v))
    }
    fn visit_u128<E: de::Error>(self, v: u128) -> Result<Val, E> {
        i64::try_from(v).map(Val::Int).map_err(|_| out_of_range(v))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Val, E> {
        Ok(Val::Float(v))
    }
    fn visit_str<E>(self, v: &str) -> Result<Val, E> {
        Ok(Val::Str(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> Result<Val, E> {
        Ok(Val::Str(v))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Val, A::Error> {
        let mut out = Vec::new();
        while let Some(n) = seq.next_element::<Node>()? {
            out.push(n);
        }
        Ok(Val::Arr(out))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Val, A::Error> {
        let mut out = Vec::new();
        while let Some(k) = map.next_key::<Spanned<String>>()? {
            let span = k.span();
            let key = k.into_inner();
            if key.starts_with("$__toml_private") {
                // A date-time arrives as a one-key map: consume and mark it.
                let _ = map.next_value::<de::IgnoredAny>()?;
                return Ok(Val::Datetime);
            }
            let v = map.next_value::<Node>()?;
            out.push((key, Origin::File(span), v));
        }
        Ok(Val::Table(out))
    }
}

/// Start of the message of an integer beyond 64 bits (not a syntax error:
/// shown without that prefix).
const OUT_OF_RANGE: &str = "the integer ";

/// An integer TOML allows but rtk cannot hold, in plain words (serde would
/// say "invalid type: integer `N` as i128").
fn out_of_range<E: de::Error>(v: impl std::fmt::Display) -> E {
    E::custom(format!(
        "{OUT_OF_RANGE}{v} is out of range: integers must be between {} and {}",
        i64::MIN,
        i64::MAX
    ))
}

/// The end of the message of a document nested beyond the parser's limit.
const TOO_DEEP: &str = "values are nested too deeply";

/// The byte range of the start of the line nested most deeply: a table
/// header's or a key's dotted parts, plus the arrays and inline tables open
/// on it (counted across lines, strings skipped). Only for pointing at a
/// nesting error, so quoted keys holding dots may count a little high.
fn deepest_line(src: &str) -> Range<usize> {
    let (mut best, mut best_depth) = (0, 0);
    let mut open = 0usize; // brackets and braces open from earlier lines
    let mut start = 0;
    for line in src.split_inclusive('\n') {
        let code = line.split('#').next().unwrap_or("");
        let t = code.trim_start();
        let header = t.starts_with('[') && open == 0;
        let key = if header {
            t.trim_start_matches('[').split(']').next().unwrap_or("")
        } else {
            t.split('=')
                .next()
                .filter(|_| t.contains('='))
                .unwrap_or("")
        };
        let mut depth = open + key.matches('.').count() + usize::from(!key.trim().is_empty());
        let mut quote: Option<char> = None;
        let value = if header { "" } else { &t[key.len()..] };
        for c in value.chars() {
            match (quote, c) {
                (Some(q), c) if c == q => quote = None,
                (Some(_), _) => {}
                (None, '"' | '\'') => quote = Some(c),
                (None, '[' | '{') => {
                    open += 1;
                    depth = depth.max(open + key.matches('.').count() + 1);
                }
                (None, ']' | '}') => open = open.saturating_sub(1),
                _ => {}
            }
        }
        if depth > best_depth {
            (best, best_depth) = (start, depth);
        }
        start += line.len();
    }
    best..best
}

/// Parse a TOML document. On a syntax error returns the message and the byte
/// range it concerns.
pub fn parse(src: &str) -> Result<Node, (String, Option<Range<usize>>)> {
    let val: Val = toml::from_str(src).map_err(|e| {
        let msg = toml_message(e.message());
        // The deserializer's recursion limit comes without a position: point
        // at the most deeply nested line, where the nesting is.
        let span = match e.span() {
            None if msg.ends_with(TOO_DEEP) => Some(deepest_line(src)),
            s => s,
        };
        (msg, span)
    })?;
    Ok(Node {
        origin: Origin::File(0..src.len()),
        value: val,
    })
}

/// The message of a TOML error, in rtk's words.
fn toml_message(raw: &str) -> String {
    let msg = raw.trim_end();
    if msg.contains("$__toml_private_datetime") {
        // toml hands a date-time to a spanned value as a private marker.
        "date-times are not used in rtk scenes".to_string()
    } else if msg.starts_with(OUT_OF_RANGE) {
        msg.to_string()
    } else if msg.contains("recursion limit") || msg.contains("cannot recurse further") {
        format!("TOML syntax error: {TOO_DEEP}")
    } else if msg == "integer too large" {
        format!(
            "{OUT_OF_RANGE}is out of range: integers must be between {} and {}",
            i64::MIN,
            i64::MAX
        )
    } else {
        format!("TOML syntax error: {msg}")
    }
}

/// Parse the value of a `--set key=value`. The rule: the value is TOML
/// (`4`, `[1, 2]`, `"text"`, `{ class = "sphere" }`); text that is not
/// TOML is taken as a string only when it is a bare word such as `main`,
/// `out.png` or `meshes/bunny.ply` ([`is_bare_word`]). Anything else —
/// `[1, 2`, `2x`, `1e999` — is refused: a typo must not become a string
/// that fails later with a confusing message, or not at all.
pub fn parse_override_value(expr: &str, text: &str) -> Result<Node, String> {
    let origin = Origin::CommandLine(expr.to_string());
    if text.is_empty() {
        return Err("the value is empty: give a TOML value, such as --set key=1".into());
    }
    let value = match toml::from_str::<Val>(&format!("v = {text}")) {
        Ok(Val::Table(mut t)) if t.len() == 1 => match t.pop() {
            Some((_, _, n)) => n.value,
            None => unreachable!("one entry"),
        },
        Ok(_) => return Err(format!("`{text}` is more than one TOML value")),
        Err(_) if is_bare_word(text) => Val::Str(text.to_string()),
        Err(e) => {
            let why = toml_message(e.message());
            if why.starts_with(OUT_OF_RANGE) {
                return Err(why);
            }
            return Err(format!(
                "`{text}` is not a TOML value ({why}); write strings other than bare words in quotes: --set 'key=\"...\"'"
            ));
        }
    };
    let mut n = Node {
        origin: origin.clone(),
        value,
    };
    reorigin(&mut n, &origin);
    Ok(n)
}

/// A bare word: starts with a letter, `_`, `.` or `/`, and holds only
/// letters, digits and `_ - . /` (names and relative or absolute paths).
pub fn is_bare_word(text: &str) -> bool {
    let ok = |c: char| c.is_alphanumeric() || "_-./".contains(c);
    text.chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || "_./".contains(c))
        && text.chars().all(ok)
}

fn reorigin(n: &mut Node, o: &Origin) {
    n.origin = o.clone();
    match &mut n.value {
        Val::Arr(a) => a.iter_mut().for_each(|c| reorigin(c, o)),
        Val::Table(t) => t.iter_mut().for_each(|(_, ko, c)| {
            *ko = o.clone();
            reorigin(c, o)
        }),
        _ => {}
    }
}

/// Line and column (1-based, columns in characters) of a byte offset.
pub fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(src.len());
    let before = &src[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rsplit('\n')
        .next()
        .map(|l| l.chars().count())
        .unwrap_or(0)
        + 1;
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_and_paths() {
        let src = "[objects.ball]\nclass = \"sphere\"\ncenter = [1.0, 2.0, nan]\n";
        let root = parse(src).unwrap();
        let ball = root.get("objects").unwrap().get("ball").unwrap();
        let n = ball.locate("center[2]");
        assert!(matches!(n.value, Val::Float(f) if f.is_nan()));
        let Origin::File(r) = &n.origin else { panic!() };
        assert_eq!(line_col(src, r.start), (3, 21));
        let Origin::File(k) = ball.locate_origin("class") else {
            panic!()
        };
        assert_eq!(line_col(src, k.start), (2, 1));
    }

    #[test]
    fn overrides() {
        let mut root = parse("[render]\nspp = 1\n").unwrap();
        root.set_path(
            &["render", "spp"],
            parse_override_value("render.spp=16", "16").unwrap(),
        )
        .unwrap();
        assert!(matches!(
            root.get("render").unwrap().get("spp").unwrap().value,
            Val::Int(16)
        ));
        let v = parse_override_value("render.camera=main", "main").unwrap();
        assert!(matches!(v.value, Val::Str(ref s) if s == "main"));
        let v = parse_override_value("render.output=out/a.png", "out/a.png").unwrap();
        assert!(matches!(v.value, Val::Str(ref s) if s == "out/a.png"));
        for bad in ["[1, 2", "2x", "1e999", "", "a b", "\"open", "-x", "1 2"] {
            let e = parse_override_value("k", bad).unwrap_err();
            assert!(
                e.contains("not a TOML value") || e.contains("empty"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn integers_beyond_64_bits_are_refused_in_plain_words() {
        for src in [
            "a = 99999999999999999999",
            "a = -9223372036854775809",
            "a = 9223372036854775808",
        ] {
            let (msg, span) = parse(src).unwrap_err();
            assert!(
                msg.contains("out of range") && !msg.contains("i128"),
                "{msg}"
            );
            assert!(span.is_some());
        }
    }

    #[test]
    fn syntax_error_has_span() {
        let (msg, span) = parse("[render]\nwidth = = 3\n").unwrap_err();
        assert!(!msg.is_empty());
        assert!(span.is_some());
    }
}
