//! Naming the key of a TOML integer out of range. TOML integers are signed
//! 64-bit, and the parser's own complaint about a larger one need not say
//! which key held it; a configuration that will not parse is searched for
//! such a literal so the error can name the key (`[model] seed`) and line.

/// An integer literal of the TOML `text` outside `i64`: its key (dotted
/// under the table it is in), its 1-based line and the literal as
/// written. `None` when there is none (the text fails for another reason).
pub(crate) fn oversized_integer(text: &str) -> Option<(String, usize, String)> {
    let mut table = String::new();
    for (n, line) in text.lines().enumerate() {
        let line = without_strings(line);
        let line = line.split('#').next().unwrap_or_default().trim();
        if line.starts_with('[') && !line.contains('=') {
            table = line
                .trim_matches(|c| c == '[' || c == ']')
                .trim()
                .to_string();
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            continue;
        };
        let separators = |c: char| c.is_whitespace() || "[]{},=".contains(c);
        if let Some(literal) = value.split(separators).find(|t| out_of_range(t)) {
            let key = key.trim().trim_matches('"');
            let key = if table.is_empty() {
                key.to_string()
            } else {
                format!("{table}.{key}")
            };
            return Some((key, n + 1, literal.to_string()));
        }
    }
    None
}

/// `line` with the contents of its quoted strings blanked, so that digits
/// inside a string are never taken for an integer.
fn without_strings(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut quote = None;
    for c in line.chars() {
        match quote {
            Some(q) if c == q => {
                quote = None;
                out.push(c);
            }
            Some(_) => out.push(' '),
            None => {
                if c == '"' || c == '\'' {
                    quote = Some(c);
                }
                out.push(c);
            }
        }
    }
    out
}

/// Whether `token` is a TOML integer literal (decimal with an optional
/// sign, or 0x / 0o / 0b; underscores between digits) outside `i64`.
fn out_of_range(token: &str) -> bool {
    let (sign, body) = match token.strip_prefix(['+', '-']) {
        Some(rest) => (&token[..1], rest),
        None => ("", token),
    };
    let digits: String = body.chars().filter(|&c| c != '_').collect();
    let (radix, digits) = match digits.get(..2) {
        Some("0x") => (16, &digits[2..]),
        Some("0o") => (8, &digits[2..]),
        Some("0b") => (2, &digits[2..]),
        _ => (10, digits.as_str()),
    };
    if digits.is_empty() || !digits.chars().all(|c| c.is_digit(radix)) {
        return false;
    }
    // Longer than any i128 holds is out of range too.
    match i128::from_str_radix(&format!("{sign}{digits}"), radix) {
        Ok(v) => i64::try_from(v).is_err(),
        Err(_) => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_key_under_its_table_and_line_are_named() {
        let text = "epochs = 3\n[model]\nseed = 9223372036854775808 # one past\n";
        let got = oversized_integer(text).unwrap();
        assert_eq!(got, ("model.seed".into(), 3, "9223372036854775808".into()));
    }

    #[test]
    fn the_limits_themselves_and_other_literals_are_not_named() {
        let text = "a = 9223372036854775807\nb = -9223372036854775808\nc = 1e300\n\
                    d = \"99999999999999999999\"\ne = 0x7fff_ffff_ffff_ffff\n";
        assert_eq!(oversized_integer(text), None);
    }

    #[test]
    fn negative_hex_array_and_huge_literals_are_named() {
        for (text, key) in [
            ("x = -9_223_372_036_854_775_809\n", "x"),
            ("[t]\ny = 0xffff_ffff_ffff_ffff\n", "t.y"),
            ("z = [1, 2, 18446744073709551616]\n", "z"),
            (&format!("w = {}\n", "9".repeat(60)), "w"),
        ] {
            assert_eq!(oversized_integer(text).unwrap().0, key, "{text}");
        }
    }
}
