//! The preview's own HTML: the index page (every dataset of the config with
//! links to its outputs, its page first) and the rewriting of a dataset's
//! page as served (each inline script given the response's nonce, the live
//! script and its style added before `</body>`). The page on disk is never
//! changed: only the served copy carries the live script. Owns the
//! `Content-Security-Policy` that goes with both.

use super::paths::{encode, Routes};
use crate::render::svg::escape as escape_html;

/// The header value for a response whose scripts carry `nonce`: nothing from
/// another origin, scripts only with the nonce or from this server, no
/// plugins, frames, forms or base changes. Styles may be inline (the page's
/// cells and swatches carry `style` attributes), but only from here.
pub(crate) fn csp(nonce: &str) -> String {
    format!(
        "default-src 'none'; script-src 'self' 'nonce-{nonce}'; style-src 'self' 'unsafe-inline'; \
         img-src 'self' data:; connect-src 'self'; base-uri 'none'; form-action 'none'; \
         frame-ancestors 'none'"
    )
}

/// The index page: a list of the datasets, each with its outputs.
pub(crate) fn index(routes: &Routes, title: &str) -> String {
    let mut out = String::from(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>",
    );
    out.push_str(&escape_html(title));
    out.push_str(
        "</title>\n<link rel=\"stylesheet\" href=\"/_np/live.css\">\n</head>\n<body class=\"np-index\">\n<h1>",
    );
    out.push_str(&escape_html(title));
    out.push_str("</h1>\n");
    if routes.datasets.is_empty() {
        out.push_str("<p>The config has no datasets yet.</p>\n");
    }
    out.push_str("<ul class=\"np-datasets\">\n");
    for (name, urls) in &routes.datasets {
        out.push_str(&format!("<li><strong>{}</strong>", escape_html(name)));
        // The interactive page first: it is the live one.
        let mut urls = urls.clone();
        urls.sort_by_key(|u| !u.ends_with(".html"));
        for url in &urls {
            // The output's path, as the config names it.
            out.push_str(&format!(
                " <a href=\"{}\">{}</a>",
                escape_html(&encode(url)),
                escape_html(url.trim_start_matches('/'))
            ));
        }
        if urls.is_empty() {
            out.push_str(" (no outputs)");
        }
        out.push_str("</li>\n");
    }
    out.push_str("</ul>\n</body>\n</html>\n");
    out
}

/// A dataset's page as served: every inline `<script>` gets `nonce`, and
/// the live script (told the dataset's name and the build key of the page,
/// `events.rs`) goes in before the last `</body>`. Our pages escape every
/// `<` of user text, so `<script>` and `</body>` only occur as the page's
/// own tags.
pub(crate) fn live_page(html: &str, dataset: &str, nonce: &str, key: &str) -> String {
    let tagged = html.replace("<script>", &format!("<script nonce=\"{nonce}\">"));
    let live = format!(
        "<link rel=\"stylesheet\" href=\"/_np/live.css\">\n\
         <script src=\"/_np/live.js\" nonce=\"{nonce}\" data-dataset=\"{}\" data-key=\"{}\" \
         data-events=\"/_np/events\"></script>\n",
        escape_html(dataset),
        escape_html(key)
    );
    match tagged.rfind("</body>") {
        Some(at) => format!("{}{live}{}", &tagged[..at], &tagged[at..]),
        None => format!("{tagged}{live}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_served_page_gets_nonces_and_the_live_script() {
        let page = "<html><body><script>a()</script><script type=\"application/json\">{}</script></body></html>";
        let served = live_page(page, "a\"b<", "N0", "k.4");
        assert!(served.contains("<script nonce=\"N0\">a()"));
        assert!(served.contains("data-dataset=\"a&quot;b&lt;\""));
        assert!(served.contains("data-key=\"k.4\""));
        assert!(served.find("/_np/live.js").expect("live") < served.find("</body>").expect("end"));
    }

    #[test]
    fn the_policy_names_no_other_origin() {
        let p = csp("x");
        assert!(p.starts_with("default-src 'none'"));
        assert!(!p.contains("http") && !p.contains('*'));
    }
}
