//! serde's messages in plain words. Plugins parse their parameters with
//! serde, whose messages speak Rust ("invalid type: floating point `1.5`,
//! expected u32", "expected struct Step with 7 elements"); the shell
//! rewrites the ones it recognises before showing them, and passes any other
//! message through unchanged.

/// A plugin's or the kernel's parameter message, in plain words.
pub fn plain_message(msg: &str) -> String {
    if let Some(rest) = msg.strip_prefix("invalid type: ") {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            return format!(
                "expected {}, found {}",
                expected_words(expected),
                found_words(found)
            );
        }
    }
    if let Some(rest) = msg.strip_prefix("invalid value: ") {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            return format!(
                "{} is out of range: expected {}",
                found_words(found),
                expected_words(expected)
            );
        }
    }
    if let Some(rest) = msg.strip_prefix("invalid length ") {
        if let Some((n, expected)) = rest.split_once(", expected ") {
            let n = n.trim();
            return format!(
                "expected {}, found {n} element{}",
                expected_words(expected),
                if n == "1" { "" } else { "s" }
            );
        }
    }
    if let Some(rest) = msg.strip_prefix("missing field ") {
        return format!("missing key {rest}");
    }
    if let Some(rest) = msg.strip_prefix("duplicate field ") {
        return format!("key {rest} given twice");
    }
    // serde_json's word for a value of a named-choice key (an enum: `bound`,
    // `normals`) that is neither a string nor a table.
    if msg == "expected value" {
        return "expected a string, one of the accepted names".to_string();
    }
    if msg == "trailing characters" {
        return "the array has too many elements".to_string();
    }
    if let Some(name) = msg.strip_prefix("data did not match any variant of untagged enum ") {
        return match name {
            "Scale" => "expected a number or an array [x, y, z]".to_string(),
            _ => "the value has none of the accepted forms".to_string(),
        };
    }
    msg.to_string()
}

/// What serde says it found, in plain words (`serde::de::Unexpected`).
fn found_words(found: &str) -> String {
    let quoted = |p: &str| {
        found
            .strip_prefix(p)
            .and_then(|r| r.strip_prefix('`'))
            .and_then(|r| r.split('`').next())
            .map(str::to_string)
    };
    if let Some(v) = quoted("integer ") {
        return format!("the integer {v}");
    }
    if let Some(v) = quoted("floating point ") {
        return format!("the number {v}");
    }
    if let Some(v) = quoted("boolean ") {
        return format!("the boolean {v}");
    }
    if let Some(s) = found.strip_prefix("string ") {
        return format!("the string {s}");
    }
    match found {
        "sequence" => "an array".to_string(),
        "map" => "a table".to_string(),
        "unit value" | "null" => "nothing".to_string(),
        other => other.to_string(),
    }
}

/// What serde says it expected, in plain words.
fn expected_words(expected: &str) -> String {
    let e = expected.trim();
    if let Some(range) = integer_range(e) {
        return range;
    }
    if e == "f32" || e == "f64" {
        return "a number".to_string();
    }
    if e.starts_with("struct ") || e == "a map" {
        return "a table".to_string();
    }
    if e == "a sequence" {
        return "an array".to_string();
    }
    if let Some(n) = e.strip_prefix("an array of length ") {
        return format!("an array of {n} elements");
    }
    if let Some(n) = e.strip_prefix("a tuple of size ") {
        return format!("an array of {n} elements");
    }
    if e.starts_with("enum ") {
        return "one of the accepted values".to_string();
    }
    e.to_string()
}

/// `u32` and its kin as the range of whole numbers they hold.
fn integer_range(e: &str) -> Option<String> {
    let (lo, hi): (i128, i128) = match e {
        "u8" => (0, u8::MAX.into()),
        "u16" => (0, u16::MAX.into()),
        "u32" => (0, u32::MAX.into()),
        "u64" | "usize" => (0, u64::MAX.into()),
        "i8" => (i8::MIN.into(), i8::MAX.into()),
        "i16" => (i16::MIN.into(), i16::MAX.into()),
        "i32" => (i32::MIN.into(), i32::MAX.into()),
        "i64" | "isize" => (i64::MIN.into(), i64::MAX.into()),
        _ => return None,
    };
    Some(format!("a whole number from {lo} to {hi}"))
}

#[cfg(test)]
mod tests {
    use super::plain_message as p;

    #[test]
    fn serde_speaks_plainly() {
        let cases = [
            (
                "invalid value: integer `-1`, expected u32",
                "the integer -1 is out of range: expected a whole number from 0 to 4294967295",
            ),
            (
                "invalid type: floating point `1.5`, expected u32",
                "expected a whole number from 0 to 4294967295, found the number 1.5",
            ),
            (
                "invalid type: string \"wide\", expected f32",
                "expected a number, found the string \"wide\"",
            ),
            (
                "invalid type: sequence, expected f32",
                "expected a number, found an array",
            ),
            (
                "invalid type: map, expected an array of length 3",
                "expected an array of 3 elements, found a table",
            ),
            (
                "invalid type: integer `1`, expected struct Step",
                "expected a table, found the integer 1",
            ),
            (
                "invalid length 0, expected struct Step with 7 elements",
                "expected a table, found 0 elements",
            ),
            (
                "invalid length 2, expected an array of length 3",
                "expected an array of 3 elements, found 2 elements",
            ),
            ("trailing characters", "the array has too many elements"),
            (
                "expected value",
                "expected a string, one of the accepted names",
            ),
            (
                "data did not match any variant of untagged enum Scale",
                "expected a number or an array [x, y, z]",
            ),
            ("missing field `file`", "missing key `file`"),
            (
                "must be a positive number, got -1",
                "must be a positive number, got -1",
            ),
        ];
        for (from, to) in cases {
            assert_eq!(p(from), to);
            for rust in ["u32", "f32", "struct", "sequence", "i128", "untagged"] {
                assert!(!p(from).contains(rust), "{from} -> {}", p(from));
            }
        }
    }
}
