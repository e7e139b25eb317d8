//! index.html: the paper's figures with their captions.

use std::path::Path;

use super::Written;

/// index.html: every figure with its caption and links to the PNG, the SVG and the data.
pub fn index_html(figures: &[Written], out: &Path, preamble: &str) -> String {
    let rel = |p: &Path| p.strip_prefix(out).unwrap_or(p).display().to_string();
    let mut html = String::from(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>eyeshell figures</title>\n<style>body{font-family:sans-serif;max-width:1200px;margin:auto;padding:1em}figure{margin:2em 0}img{max-width:100%;border:1px solid #ccc}figcaption{margin-top:.5em;line-height:1.4}</style>\n</head>\n<body>\n<h1>eyeshell: the paper's result figures</h1>\n",
    );
    html.push_str(&format!("<p>{}</p>\n", escape(preamble)));
    for f in figures {
        html.push_str(&format!(
            "<figure id=\"fig-{id}\">\n<h2>({id}) {title}</h2>\n<img src=\"{png}\" alt=\"({id}) {title}\">\n<figcaption>{caption} <a href=\"{png}\">PNG</a> · <a href=\"{svg}\">SVG</a></figcaption>\n</figure>\n",
            id = escape(&f.id),
            title = escape(&f.title),
            png = escape(&rel(&f.png)),
            svg = escape(&rel(&f.svg)),
            caption = escape(&f.caption)
        ));
    }
    html.push_str("</body>\n</html>\n");
    html
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
