//! Mutations of one input file: byte-level (bit flips, inserts, deletes,
//! truncation, chunk duplication, interesting numbers), text-level (number
//! tokens, lines, CSV columns) and structure-aware (TOML and JSON trees,
//! PNG pixels, raw floats inside binary arrays).
use rand::seq::IndexedRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// What a file is, to pick the mutations that reach past its parser.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Csv,
    Toml,
    Json,
    /// Binary with a text header and float payload (.npy, .safetensors).
    Array,
}

/// Text that parsers tend to get wrong.
const WORDS: &[&str] = &[
    "0",
    "-1",
    "-0",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-320",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551616",
    "99999999999999999999999999",
    "0.5",
    "",
    "\"\"",
    "true",
    "[]",
    "{}",
    "null",
    "x",
    "\u{feff}",
    "\u{fffd}",
    ",",
    "\"",
];

/// Raw values for binary payloads (little-endian f32/f64/u64).
fn raw_values() -> Vec<Vec<u8>> {
    let mut v: Vec<Vec<u8>> = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
        0.0,
        -1.0,
    ]
    .iter()
    .map(|f| f.to_le_bytes().to_vec())
    .collect();
    v.push(f64::NAN.to_le_bytes().to_vec());
    v.push(1e308f64.to_le_bytes().to_vec());
    v.push(u64::MAX.to_le_bytes().to_vec());
    v.push((1u64 << 40).to_le_bytes().to_vec());
    v.push(vec![0xff, 0xfe, 0xfd]);
    v
}

/// The largest input a mutation may make (stacked mutations that grow a
/// file, such as a line repeated thousands of times, are cut here so the
/// fuzzer itself stays within memory).
const MAX_INPUT_BYTES: usize = 4 << 20;

/// One to three stacked random mutations of `data`, chosen to suit
/// `format`; named by the last one. Never longer than `MAX_INPUT_BYTES`.
pub fn mutate(data: &[u8], format: Format, rng: &mut ChaCha8Rng) -> (Vec<u8>, &'static str) {
    let rounds = [1, 1, 1, 2, 3][rng.random_range(0..5)];
    let mut out = (data.to_vec(), "unchanged");
    for _ in 0..rounds {
        out = mutate_once(&out.0, format, rng);
        out.0.truncate(MAX_INPUT_BYTES);
    }
    out
}

/// One random mutation of `data`, chosen to suit `format`.
fn mutate_once(data: &[u8], format: Format, rng: &mut ChaCha8Rng) -> (Vec<u8>, &'static str) {
    let structured = rng.random_bool(0.5);
    let got = if structured {
        structured_mutation(data, format, rng)
    } else {
        None
    };
    match got {
        Some(found) => found,
        None => byte_mutation(data, rng),
    }
}

/// A format-aware mutation, or None when it does not apply.
fn structured_mutation(
    data: &[u8],
    format: Format,
    rng: &mut ChaCha8Rng,
) -> Option<(Vec<u8>, &'static str)> {
    match format {
        Format::Png => super::image_mut::mutate_png(data, rng),
        Format::Csv => text_mutation(data, rng, true),
        Format::Toml => match rng.random_range(0..3) {
            0 => super::tree_mut::mutate_toml(data, rng),
            _ => text_mutation(data, rng, false),
        },
        Format::Json => match rng.random_range(0..3) {
            0 => text_mutation(data, rng, false),
            _ => super::tree_mut::mutate_json(data, rng),
        },
        Format::Array => array_mutation(data, rng),
    }
}

/// Bit flips, inserts, deletes, truncation, duplication, interesting bytes.
pub fn byte_mutation(data: &[u8], rng: &mut ChaCha8Rng) -> (Vec<u8>, &'static str) {
    let mut d = data.to_vec();
    let n = d.len().max(1);
    let at = rng.random_range(0..n).min(d.len());
    let name = match rng.random_range(0..8) {
        0 => {
            for _ in 0..rng.random_range(1..=8) {
                if let Some(b) = d.get_mut(rng.random_range(0..n)) {
                    *b ^= 1 << rng.random_range(0..8);
                }
            }
            "bit flips"
        }
        1 => {
            let len = rng.random_range(1..64);
            let bytes: Vec<u8> = (0..len).map(|_| rng.random()).collect();
            d.splice(at..at, bytes);
            "byte insert"
        }
        2 => {
            let end = (at + rng.random_range(1..256)).min(d.len());
            d.drain(at..end);
            "byte delete"
        }
        3 => {
            d.truncate(at);
            "truncation"
        }
        4 => {
            let end = (at + rng.random_range(1..512)).min(d.len());
            let chunk = d[at..end].to_vec();
            let to = rng.random_range(0..=d.len());
            d.splice(to..to, chunk.iter().copied().cycle().take(chunk.len() * 3));
            "chunk duplication"
        }
        5 => {
            d.clear();
            "empty"
        }
        6 => {
            let raw = raw_values();
            let v = raw.choose(rng).expect("values");
            let end = (at + v.len()).min(d.len());
            d.splice(at..end, v.iter().copied());
            "interesting bytes"
        }
        _ => return number_tokens(data, rng).unwrap_or_else(|| (data.to_vec(), "unchanged")),
    };
    (d, name)
}

/// Replace one ASCII number token (also inside binary headers) by a word.
fn number_tokens(data: &[u8], rng: &mut ChaCha8Rng) -> Option<(Vec<u8>, &'static str)> {
    let spans = digit_runs(data);
    let &(s, e) = spans.choose(rng)?;
    let word = WORDS.choose(rng)?.as_bytes();
    let mut d = data.to_vec();
    d.splice(s..e, word.iter().copied());
    Some((d, "number token"))
}

/// The (start, end) of every run of ASCII digits, signs, dots and exponents.
fn digit_runs(data: &[u8]) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut i = 0;
    while i < data.len() {
        if data[i].is_ascii_digit() {
            let s = i;
            while i < data.len() && (data[i].is_ascii_digit() || b".eE-+".contains(&data[i])) {
                i += 1;
            }
            runs.push((s, i));
        } else {
            i += 1;
        }
    }
    runs
}

/// Line and CSV-aware edits of a text file.
fn text_mutation(data: &[u8], rng: &mut ChaCha8Rng, csv: bool) -> Option<(Vec<u8>, &'static str)> {
    let text = std::str::from_utf8(data).ok()?;
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    if lines.is_empty() {
        return None;
    }
    let i = rng.random_range(0..lines.len());
    let name = match rng.random_range(0..8) {
        0 => {
            lines.remove(0);
            "missing header"
        }
        1 => {
            let l = lines[i].clone();
            lines.insert(i, l);
            "duplicate line"
        }
        2 => {
            lines.remove(i);
            "delete line"
        }
        3 => {
            let times = rng
                .random_range(200..3000)
                .min(MAX_INPUT_BYTES / lines[i].len().max(1));
            lines[i] = lines[i].repeat(times.max(1));
            "very long line"
        }
        4 => {
            let mut bytes = lines.join("\n").into_bytes();
            let at = rng.random_range(0..=bytes.len());
            bytes.splice(at..at, [0xff, 0xc3, 0x28, 0x00]);
            return Some((bytes, "non-UTF-8"));
        }
        5 if csv => return Some((swap_columns(&lines, rng), "swapped columns")),
        6 if csv => {
            let l = lines.len();
            lines.truncate(rng.random_range(0..l.min(4)));
            "few rows"
        }
        _ => {
            let word = WORDS.choose(rng)?;
            lines[i] = replace_cell(&lines[i], word, rng);
            "interesting value"
        }
    };
    Some((lines.join("\n").into_bytes(), name))
}

/// Swap two comma-separated columns on every line.
fn swap_columns(lines: &[String], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let width = lines[0].split(',').count();
    let (a, b) = (rng.random_range(0..width), rng.random_range(0..width));
    let out: Vec<String> = lines
        .iter()
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            if a < cells.len() && b < cells.len() {
                cells.swap(a, b);
            }
            cells.join(",")
        })
        .collect();
    out.join("\n").into_bytes()
}

/// Replace one field (split on `,`, `=` or space) of a line by `word`.
fn replace_cell(line: &str, word: &str, rng: &mut ChaCha8Rng) -> String {
    let sep = [',', '=', ' ']
        .into_iter()
        .find(|c| line.contains(*c))
        .unwrap_or(',');
    let mut cells: Vec<String> = line.split(sep).map(str::to_owned).collect();
    let k = rng.random_range(0..cells.len());
    cells[k] = if sep == '=' && k > 0 {
        format!(" {word}")
    } else {
        word.to_owned()
    };
    cells.join(&sep.to_string())
}

/// Overwrite floats in the payload of an .npy or .safetensors file.
fn array_mutation(data: &[u8], rng: &mut ChaCha8Rng) -> Option<(Vec<u8>, &'static str)> {
    if rng.random_bool(0.4) {
        return number_tokens(&data[..data.len().min(400)], rng).map(|(mut head, name)| {
            head.extend_from_slice(&data[data.len().min(400)..]);
            (head, name)
        });
    }
    let start = data.len().min(256);
    if data.len() < start + 8 {
        return None;
    }
    let mut d = data.to_vec();
    let raw = raw_values();
    for _ in 0..rng.random_range(1..6) {
        let v = raw.choose(rng)?;
        let at = rng.random_range(start..d.len() - 8) & !3;
        d[at..at + v.len()].copy_from_slice(v);
    }
    Some((d, "payload floats"))
}
