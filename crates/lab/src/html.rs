//! A small renderer from the report's own Markdown (headings, paragraphs,
//! pipe tables, images) to a standalone HTML page. It handles only what
//! tactrace writes, not Markdown at large. Images can be embedded as data
//! URIs (the caller reads the files), so the page is self-contained.

/// Maps an image `src` to what the page should load instead (a data URI),
/// or `None` to keep the link.
pub type Embed<'a> = &'a dyn Fn(&str) -> Option<String>;

/// Escape text for HTML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Inline images `![alt](src)` in a line become `<img>`; the rest is escaped.
fn inline(line: &str, embed: Embed) -> String {
    let mut out = String::new();
    let mut rest = line;
    while let Some(start) = rest.find("![") {
        let Some(mid) = rest[start..].find("](").map(|m| start + m) else {
            break;
        };
        let Some(end) = rest[mid..].find(')').map(|e| mid + e) else {
            break;
        };
        out.push_str(&esc(&rest[..start]));
        let (alt, src) = (&rest[start + 2..mid], &rest[mid + 2..end]);
        let src = embed(src).unwrap_or_else(|| src.to_owned());
        out.push_str(&format!(
            "<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
            esc(&src),
            esc(alt),
            esc(alt)
        ));
        rest = &rest[end + 1..];
    }
    out.push_str(&esc(rest));
    out
}

fn cells(line: &str) -> Vec<&str> {
    line.trim()
        .trim_matches('|')
        .split('|')
        .map(str::trim)
        .collect()
}

/// Render tactrace's Markdown as a complete HTML document, images passed
/// through `embed`.
pub fn markdown_to_html(md: &str, embed: Embed) -> String {
    let mut body = String::new();
    let lines: Vec<&str> = md.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        if let Some(h) = line.strip_prefix("## ") {
            body.push_str(&format!("<h2>{}</h2>\n", esc(h)));
        } else if let Some(h) = line.strip_prefix("# ") {
            body.push_str(&format!("<h1>{}</h1>\n", esc(h)));
        } else if line.starts_with('|') {
            body.push_str("<table>\n");
            let head = cells(line);
            body.push_str(&format!(
                "<tr>{}</tr>\n",
                head.iter()
                    .map(|c| format!("<th>{}</th>", esc(c)))
                    .collect::<String>()
            ));
            i += 2; // skip the separator row
            while i < lines.len() && lines[i].starts_with('|') {
                body.push_str(&format!(
                    "<tr>{}</tr>\n",
                    cells(lines[i])
                        .iter()
                        .map(|c| format!("<td>{}</td>", esc(c)))
                        .collect::<String>()
                ));
                i += 1;
            }
            body.push_str("</table>\n");
            continue;
        } else if !line.trim().is_empty() {
            body.push_str(&format!("<p>{}</p>\n", inline(line, embed)));
        }
        i += 1;
    }
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>tactrace report</title>\n<style>{}</style></head>\n<body>\n{body}</body></html>\n",
        "body{font-family:sans-serif;max-width:1250px;margin:2em auto;padding:0 1em}table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:.3em .6em;text-align:right}th{background:#eee}figure{display:inline-block;margin:.5em}img{max-width:100%}figure img{max-height:560px}figcaption{font-size:.85em;color:#555}"
    )
}

#[cfg(test)]
mod tests {
    use super::markdown_to_html;

    #[test]
    fn renders_tables_and_images() {
        let md = "# T\n\n| a | b |\n|---|---|\n| 1 | <2> |\n\n![cap](f.svg) ![other](g.svg)\n";
        let embed = |src: &str| (src == "g.svg").then(|| "data:x".to_owned());
        let html = markdown_to_html(md, &embed);
        assert!(html.contains("<h1>T</h1>"));
        assert!(html.contains("<td>&lt;2&gt;</td>"));
        assert!(html.contains("<img src=\"f.svg\" alt=\"cap\">"));
        assert!(html.contains("<img src=\"data:x\" alt=\"other\">"));
    }
}
