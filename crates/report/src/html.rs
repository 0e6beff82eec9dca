//! The report's Markdown as a standalone HTML page (CommonMark with pipe
//! tables, by pulldown-cmark). Images can be embedded as data URIs (the
//! caller reads the files), so the page is self-contained.
use pulldown_cmark::{html, Event, Options, Parser, Tag};

/// Maps an image `src` to what the page should load instead (a data URI),
/// or `None` to keep the link.
pub type Embed<'a> = &'a dyn Fn(&str) -> Option<String>;

const STYLE: &str = "body{font-family:sans-serif;max-width:1250px;margin:2em auto;padding:0 1em}table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:.3em .6em;text-align:right}th{background:#eee}img{max-width:100%;max-height:560px;margin:.5em}";

/// Render Markdown as a complete HTML document, images passed through `embed`.
pub fn markdown_to_html(md: &str, embed: Embed) -> String {
    let parser = Parser::new_ext(md, Options::ENABLE_TABLES).map(|event| match event {
        Event::Start(Tag::Image {
            link_type,
            dest_url,
            title,
            id,
        }) => {
            let dest_url = embed(&dest_url).map(Into::into).unwrap_or(dest_url);
            Event::Start(Tag::Image {
                link_type,
                dest_url,
                title,
                id,
            })
        }
        other => other,
    });
    let mut body = String::new();
    html::push_html(&mut body, parser);
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>tactrace report</title>\n<style>{STYLE}</style></head>\n<body>\n{body}</body></html>\n"
    )
}

#[cfg(test)]
mod tests {
    use super::markdown_to_html;

    #[test]
    fn renders_tables_of_any_shape_and_embeds_images() {
        let md =
            "# T\n\n| a | b | c |\n|---|---|---|\n| 1 | <2> |\n\n![cap](f.svg) ![other](g.svg)\n";
        let embed = |src: &str| (src == "g.svg").then(|| "data:x".to_owned());
        let html = markdown_to_html(md, &embed);
        assert!(html.contains("<h1>T</h1>"), "{html}");
        assert!(html.contains("<td>&lt;2&gt;</td>"), "{html}");
        assert!(html.contains("<th>c</th>"), "{html}");
        assert!(html.contains("src=\"f.svg\" alt=\"cap\""), "{html}");
        assert!(html.contains("src=\"data:x\" alt=\"other\""), "{html}");
    }
}
