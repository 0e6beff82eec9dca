//! Tests only: every `tactrace ...` command line in README.md and docs/ (docs/results/ too)
//! parses with the CLI's own clap definition, so the docs cannot name an
//! option, a value or a subcommand that does not exist.
//!
//! Shell code blocks are read line by line (continuations joined, comments,
//! pipes, redirections and `VAR=value` prefixes handled, `$VAR` expanded
//! from the block's assignments and `for` loops); a command is one that
//! runs `tactrace`, `$T` (`T=target/release/tactrace`),
//! `target/release/tactrace` or `cargo run --release --`. Synopsis
//! notation is read as the README writes it: `[...]` is optional, `(A |
//! B)` a choice, `a|b` a choice of values, ALL-CAPS words placeholders.
//! Every option anywhere on the line must exist for its subcommand, and
//! the line with its optional parts left out and the first of each choice
//! must parse. Inline code in prose that starts with `tactrace`, or with
//! a subcommand and an option (`train --val-fraction 0.2`), gets the
//! first check.

use crate::Cli;
use clap::{CommandFactory, Parser};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// One command found in a document.
#[derive(Debug)]
struct Found {
    line: usize,
    /// The arguments after the program name, in synopsis notation.
    args: Vec<String>,
    /// From a shell block (parsed in full) or inline prose (options only).
    block: bool,
}

/// The user documents: README.md, docs/*.md and docs/results/*.md.
fn documents() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("README.md")];
    let mut docs: Vec<PathBuf> = ["docs", "docs/results"]
        .iter()
        .flat_map(|dir| std::fs::read_dir(root.join(dir)).expect("docs/ is readable"))
        .map(|e| e.expect("a docs entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// Splits a shell line into words (quotes kept together, unquoted).
fn words(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut quote: Option<char> = None;
    let mut any = false;
    for c in line.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.push(c),
            (None, '"' | '\'') => {
                quote = Some(c);
                any = true;
            }
            (None, c) if c.is_whitespace() => {
                if any || !word.is_empty() {
                    out.push(std::mem::take(&mut word));
                }
                any = false;
            }
            (None, c) => word.push(c),
        }
    }
    if any || !word.is_empty() {
        out.push(word);
    }
    out
}

/// The line without a `#` comment (one that starts a word).
fn without_comment(line: &str) -> &str {
    let bytes = line.as_bytes();
    let mut quote = None;
    for (i, &b) in bytes.iter().enumerate() {
        match (quote, b) {
            (Some(q), b) if b == q => quote = None,
            (Some(_), _) => {}
            (None, b'"' | b'\'') => quote = Some(b),
            (None, b'#') if i == 0 || bytes[i - 1].is_ascii_whitespace() => return &line[..i],
            _ => {}
        }
    }
    line
}

/// `$NAME` and `${NAME}` replaced by their values (unknown: "x").
fn expand(word: &str, vars: &HashMap<String, String>) -> String {
    let mut out = String::new();
    let mut rest = word;
    while let Some(at) = rest.find('$') {
        out.push_str(&rest[..at]);
        let after = &rest[at + 1..];
        let (name, tail) = match after.strip_prefix('{') {
            Some(inner) => match inner.find('}') {
                Some(end) => (&inner[..end], &inner[end + 1..]),
                None => (inner, ""),
            },
            None => {
                let end = after
                    .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                    .unwrap_or(after.len());
                (&after[..end], &after[end..])
            }
        };
        out.push_str(vars.get(name).map_or("x", String::as_str));
        rest = tail;
    }
    out.push_str(rest);
    out
}

/// The arguments of a tactrace invocation in `segment`, if it is one.
fn invocation(segment: &[String]) -> Option<Vec<String>> {
    let start = segment
        .iter()
        .position(|w| !w.contains('=') || w.starts_with('-'))?;
    let rest = &segment[start..];
    let program = rest.first()?.as_str();
    if program.ends_with("target/release/tactrace") || program == "tactrace" {
        return Some(rest[1..].to_vec());
    }
    if program == "cargo" && rest.get(1).map(String::as_str) == Some("run") {
        let dashes = rest.iter().position(|w| w == "--")?;
        // `cargo run -p other` or `--example x` runs something else.
        let other = ["-p", "--package", "--example", "--bin"];
        if rest[..dashes].iter().any(|w| other.contains(&w.as_str())) {
            return None;
        }
        return Some(rest[dashes + 1..].to_vec());
    }
    None
}

/// The commands of one shell line: split at `;`, `&&`, `||` and pipes
/// outside synopsis groups, redirections dropped.
fn commands_of_line(line: &str, vars: &HashMap<String, String>) -> Vec<Vec<String>> {
    let mut segments: Vec<Vec<String>> = vec![Vec::new()];
    let mut depth = 0i32;
    let mut skip_next = false;
    for raw in words(without_comment(line)) {
        if skip_next {
            skip_next = false;
            continue;
        }
        depth += raw.matches(['(', '[']).count() as i32;
        let closing = raw.matches([')', ']']).count() as i32;
        let word = expand(&raw, vars);
        let separator = matches!(word.as_str(), ";" | "&&" | "||" | "do" | "then")
            || (word == "|" && depth == 0);
        if separator {
            segments.push(Vec::new());
        } else if word == ">" || word == "2>" || word == ">>" {
            skip_next = true;
        } else if word.starts_with('>') || word.starts_with("2>") {
        } else if let Some(stripped) = word.strip_suffix(';') {
            segments.last_mut().unwrap().push(stripped.to_owned());
            segments.push(Vec::new());
        } else if raw.starts_with('$') {
            // An unquoted variable splits into words as the shell splits it.
            let words = word.split_whitespace().map(str::to_owned);
            segments.last_mut().unwrap().extend(words);
        } else {
            segments.last_mut().unwrap().push(word);
        }
        depth -= closing;
    }
    segments.iter().filter_map(|s| invocation(s)).collect()
}

/// `NAME=value` alone on a line, and `for NAME in first ...`.
fn learn_vars(line: &str, vars: &mut HashMap<String, String>) {
    let w = words(without_comment(line));
    if w.first().map(String::as_str) == Some("for") && w.get(2).map(String::as_str) == Some("in") {
        if let (Some(name), Some(first)) = (w.get(1), w.get(3)) {
            vars.insert(name.clone(), first.trim_end_matches(';').to_owned());
        }
        return;
    }
    for word in w
        .iter()
        .take_while(|w| w.contains('=') && !w.starts_with('-'))
    {
        let word = word.trim_end_matches(';');
        if let Some((name, value)) = word.split_once('=') {
            let value = expand(value, vars);
            vars.insert(name.to_owned(), value);
        }
    }
}

/// Every command of one document.
fn commands_in(file: &Path) -> Vec<Found> {
    let text = std::fs::read_to_string(file).expect("a document reads");
    let mut found = Vec::new();
    // The docs' conventions, stated once in prose ("`T=target/release/tactrace`"):
    // blocks may use $T and $D without setting them; a block's own
    // assignments hold for the rest of the file.
    let mut vars: HashMap<String, String> = [
        ("T", "target/release/tactrace"),
        ("D", "../shared/data/tactip127-edge2d"),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    let mut block: Option<bool> = None; // Some(is a shell block)
    let mut pending = String::new();
    let mut pending_line = 0;
    let mut prose = String::new();
    let mut prose_line = 0;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(lang) = trimmed.strip_prefix("```") {
            block = match block {
                Some(_) => None,
                None => Some(matches!(
                    lang.trim(),
                    "" | "sh" | "bash" | "shell" | "console"
                )),
            };
            continue;
        }
        match block {
            Some(true) => {
                if pending.is_empty() {
                    pending_line = i + 1;
                }
                let body = trimmed.strip_prefix("$ ").unwrap_or(trimmed);
                match body.strip_suffix('\\') {
                    Some(head) => {
                        pending.push_str(head);
                        pending.push(' ');
                        continue;
                    }
                    None => pending.push_str(body),
                }
                let logical = std::mem::take(&mut pending);
                learn_vars(&logical, &mut vars);
                for args in commands_of_line(&logical, &vars) {
                    found.push(Found {
                        line: pending_line,
                        args,
                        block: true,
                    });
                }
            }
            Some(false) => {}
            None => {
                if prose.is_empty() {
                    prose_line = i + 1;
                }
                if line.trim().is_empty() {
                    found.extend(inline_commands(prose_line, &prose));
                    prose.clear();
                } else {
                    prose.push_str(line);
                    prose.push('\n');
                }
            }
        }
    }
    found.extend(inline_commands(prose_line, &prose));
    found
}

/// The inline code spans of a paragraph that start with `tactrace `.
fn inline_commands(line: usize, paragraph: &str) -> Vec<Found> {
    paragraph
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|span| span.replace('\n', " "))
        .filter_map(|span| {
            let args = match span.strip_prefix("tactrace ") {
                Some(rest) => words(rest),
                // `train --val-fraction 0.2`: a subcommand with options.
                None => {
                    let w = words(&span);
                    let sub = w.first()?;
                    let known = Cli::command().find_subcommand(sub).is_some();
                    (known && w.iter().any(|a| a.starts_with("--"))).then_some(w)?
                }
            };
            Some(Found {
                line,
                args,
                block: false,
            })
        })
        .collect()
}

/// A placeholder word: capitals, digits and `_` only (FRAME, N, RIG).
fn placeholder(word: &str) -> bool {
    word.chars().any(|c| c.is_ascii_uppercase())
        && word
            .chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
}

/// Synopsis words with their brackets split off: "[--a" -> "[", "--a".
fn tokens(args: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    for w in args {
        let lead = w.len() - w.trim_start_matches(['[', '(']).len();
        let core = w.trim_start_matches(['[', '(']);
        // Brackets opened inside the word close inside it
        // (`COLUMN:UNIT[:circular]`); only the closers beyond them end groups.
        let mut inner = 0usize;
        let mut cut = core.len();
        for (i, c) in core.char_indices() {
            match c {
                '[' | '(' => inner += 1,
                ']' | ')' if inner == 0 => {
                    cut = i;
                    break;
                }
                ']' | ')' => inner -= 1,
                _ => {}
            }
        }
        let (body, trail) = core.split_at(cut);
        out.extend(w[..lead].chars().map(String::from));
        if !body.is_empty() {
            out.push(body.to_owned());
        }
        out.extend(trail.chars().map(String::from));
    }
    out
}

/// The synopsis with every `[...]` left out, the first choice of each
/// `(A | B)` and of each `a|b` value, placeholders as "1".
fn required(tokens: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    let mut optional = 0;
    // Per open parenthesis: whether its first choice is over.
    let mut groups: Vec<bool> = Vec::new();
    for t in tokens {
        match t.as_str() {
            "[" => optional += 1,
            "]" => optional -= 1,
            "(" => groups.push(false),
            ")" => {
                groups.pop();
            }
            "|" => {
                if let Some(done) = groups.last_mut() {
                    *done = true;
                }
            }
            "..." => {}
            word if optional == 0 && !groups.iter().any(|&done| done) => {
                let first = if word.starts_with('-') {
                    word
                } else {
                    word.split('|').next().unwrap_or(word)
                };
                out.push(if placeholder(first) {
                    "1".to_owned()
                } else {
                    first.to_owned()
                });
            }
            _ => {}
        }
    }
    out
}

/// The subcommand a line runs, and the options that line names that it
/// does not have.
fn unknown_options(tokens: &[String]) -> Vec<String> {
    let root = Cli::command();
    let mut cmd = &root;
    let mut rest = tokens;
    while let Some((first, tail)) = rest.split_first() {
        match cmd.find_subcommand(first) {
            Some(sub) => {
                cmd = sub;
                rest = tail;
            }
            None => break,
        }
    }
    let known: Vec<String> = cmd
        .get_arguments()
        .filter_map(|a| a.get_long().map(|l| format!("--{l}")))
        .chain(["--help".to_owned(), "--version".to_owned()])
        .collect();
    rest.iter()
        .filter(|t| t.starts_with("--") && t.len() > 2)
        .map(|t| t.split('=').next().unwrap_or(t).to_owned())
        .filter(|t| !known.contains(t))
        .collect()
}

/// What is wrong with one command, if anything.
fn problem(found: &Found) -> Option<String> {
    if found
        .args
        .first()
        .is_none_or(|a| placeholder(a) || a.starts_with('-'))
    {
        return None; // `tactrace COMMAND --help`, `tactrace --help`
    }
    let tokens = tokens(&found.args);
    let unknown = unknown_options(&tokens);
    if !unknown.is_empty() {
        return Some(format!("unknown options {}", unknown.join(", ")));
    }
    if !found.block {
        return None;
    }
    let args = required(&tokens);
    match Cli::try_parse_from(std::iter::once("tactrace".to_owned()).chain(args.clone())) {
        Ok(_) => None,
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
            ) =>
        {
            None
        }
        Err(e) => Some(format!("`tactrace {}` does not parse: {e}", args.join(" "))),
    }
}

/// Issue 20: the docs are checked against the code. Every `tactrace`
/// command line of README.md and docs/ (docs/results/ too) names existing subcommands and
/// options, and the shell lines parse.
#[test]
fn every_documented_command_parses() {
    let mut checked = 0;
    let mut problems = Vec::new();
    for file in documents() {
        for found in commands_in(&file) {
            checked += 1;
            if let Some(p) = problem(&found) {
                problems.push(format!(
                    "{}:{}: `tactrace {}`: {p}",
                    file.file_name().unwrap().to_string_lossy(),
                    found.line,
                    found.args.join(" ")
                ));
            }
        }
    }
    assert!(checked > 100, "only {checked} commands found");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The checker itself: synopsis notation, variables and pipes.
#[test]
fn the_doc_command_checker_reads_synopses_and_shell() {
    let mut vars = HashMap::new();
    learn_vars("T=target/release/tactrace; D=../data", &mut vars);
    let cmds = commands_of_line("$T validate --model m --data $D/val | head # note", &vars);
    assert_eq!(cmds, vec![words("validate --model m --data ../data/val")]);
    let syn = tokens(&words(
        "train --model pdennn|mlp --train d (--val v | --val-fraction 0.2 [--split-seed 1]) --out m [--epochs N]",
    ));
    assert_eq!(
        required(&syn),
        words("train --model pdennn --train d --val v --out m")
    );
    let bad = Found {
        line: 1,
        args: words("follow --model m --shape disk --no-such-flag --out r"),
        block: true,
    };
    assert!(problem(&bad).is_some_and(|p| p.contains("--no-such-flag")));
    let unparsable = Found {
        args: words("train --model nosuchkind --train d --out m"),
        ..bad
    };
    assert!(problem(&unparsable).is_some_and(|p| p.contains("does not parse")));
    // An unquoted variable holding options splits into words.
    learn_vars("TG=\"--target a:mm --target b:deg\"", &mut vars);
    let cmds = commands_of_line("$T import --frames f $TG --out d", &vars);
    assert_eq!(
        cmds,
        vec![words(
            "import --frames f --target a:mm --target b:deg --out d"
        )]
    );
    // A bracket inside a word does not end the optional group round it.
    let syn = tokens(&words(
        "twin --targets t [--target COLUMN:UNIT[:circular] ...] --out d",
    ));
    assert_eq!(required(&syn), words("twin --targets t --out d"));
}
