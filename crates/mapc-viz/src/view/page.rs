//! The page's HTML, built so that nothing a map says can run in it: maps come from the internet, and a road's
//! class, name or id is any text its author chose.
//!
//! Three guards, each enough on its own against the text the page shows:
//! - the data rides in a `<script type="application/json">` block with `<`, `>`, `&`, U+2028 and U+2029 written
//!   as `\uXXXX`, so no map text can end that element (`</script>`) or change how the HTML parser reads it
//!   (`<!--`), and `JSON.parse` gives back the same strings;
//! - the page's script puts map text on the page only as text (DOM nodes, `textContent`, canvas), never as HTML;
//! - a Content-Security-Policy lets only the page's own script and style run (by their SHA-256), and loads or
//!   sends nothing: an element that slipped in could neither run a script nor reach the network.

use base64::Engine;
use sha2::{Digest, Sha256};

const TEMPLATE: &str = include_str!("assets/page.html");
/// The page's own script, as it stands between `<script>` and `</script>` (its hash is over exactly this text).
pub const SCRIPT: &str = include_str!("assets/viewer.js");
/// The page's own style sheet, as it stands between `<style>` and `</style>`.
pub const STYLE: &str = include_str!("assets/viewer.css");

/// How the page gets its data, which decides what it may connect to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Delivery {
    /// A file with its data inline: it connects nowhere.
    File,
    /// `mapc view --serve`: it fetches `data.json` from where it was served, and nothing else.
    Served,
}

/// The Content-Security-Policy of a page: the page's `<meta http-equiv>` and, when served, the same as a response
/// header. Nothing is allowed unless named: no script but the page's own (by hash, so not even an inline event
/// handler), no style sheet but its own, no image, frame, font or form, and no connection but `data.json` when
/// served. Trusted Types make the browser refuse any HTML parsed from a string in the page's script.
pub fn content_security_policy(delivery: Delivery) -> String {
    let connect = match delivery {
        Delivery::File => "'none'",
        Delivery::Served => "'self'",
    };
    format!(
        "default-src 'none'; script-src '{}'; style-src '{}'; connect-src {connect}; base-uri 'none'; \
         form-action 'none'; require-trusted-types-for 'script'; trusted-types 'none'",
        hash_source(SCRIPT),
        hash_source(STYLE)
    )
}

/// A CSP hash source, `sha256-BASE64`, of an inline element's exact text.
pub fn hash_source(text: &str) -> String {
    let digest = Sha256::digest(text.as_bytes());
    format!(
        "sha256-{}",
        base64::engine::general_purpose::STANDARD.encode(digest)
    )
}

/// The JSON text for a `<script type="application/json">` block. `<`, `>` and `&` occur in serde_json's output
/// only inside strings, where `\u003c` means the same character to `JSON.parse` and nothing to the HTML parser;
/// U+2028 and U+2029 are escaped too, as some tools still read them as line ends.
pub fn embed_json(json: &str) -> String {
    let mut out = String::with_capacity(json.len() + json.len() / 64);
    for c in json.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    out
}

/// The page: `data` (JSON) inline for a file, none when served.
pub fn page_html(title: &str, data: Option<&str>, delivery: Delivery) -> String {
    let data = data
        .map(|json| {
            format!(
                "<script type=\"application/json\" id=\"mapc-data\">{}</script>",
                embed_json(json)
            )
        })
        .unwrap_or_default();
    let csp = content_security_policy(delivery);
    let title = text_escape(title);
    // one pass over the template: a value that happens to contain `{{DATA}}` stays text
    fill(TEMPLATE, |name| match name {
        "CSP" => &csp,
        "TITLE" => &title,
        "STYLE" => STYLE,
        "SCRIPT" => SCRIPT,
        "DATA" => &data,
        other => panic!("page.html names no value `{other}`"),
    })
}

/// Replace every `{{NAME}}` in `template` by `value(NAME)`, scanning the template only.
fn fill<'a>(template: &str, value: impl Fn(&str) -> &'a str) -> String {
    let mut out = String::with_capacity(template.len() + SCRIPT.len() + STYLE.len());
    let mut rest = template;
    while let Some(open) = rest.find("{{") {
        out.push_str(&rest[..open]);
        let after = &rest[open + 2..];
        let close = after.find("}}").expect("page.html closes its markers");
        out.push_str(value(&after[..close]));
        rest = &after[close + 2..];
    }
    out.push_str(rest);
    out
}

/// Text for an element's content (`<title>`) or a double-quoted attribute.
fn text_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::ViewPage;
    use mapc_scenario::SimpleMergeParams;
    use mapc_scenario::generator::simple_merge;

    /// Text a map could carry that would end, comment out or rewrite the page's elements if it were taken as HTML.
    const HOSTILE: [&str; 6] = [
        "<img src=x onerror=document.body.dataset.pwned=1>",
        "</script><script>document.body.dataset.pwned=2</script>",
        "<!--<script>",
        "</SCRIPT >&amp;{{DATA}}{{SCRIPT}}",
        "line\u{2028}separator\u{2029}paragraph",
        "\"'`\\ ]]> -->",
    ];

    /// The text of the one element `<tag ...>` whose opening tag contains `marker`.
    fn element_text<'a>(html: &'a str, marker: &str) -> &'a str {
        let at = html.find(marker).unwrap_or_else(|| panic!("no {marker}"));
        let start = at + html[at..].find('>').unwrap() + 1;
        &html[start..start + html[start..].find("</").unwrap()]
    }

    fn hostile_page() -> ViewPage {
        let mut graph = simple_merge(&SimpleMergeParams::default()).unwrap();
        for (i, road) in graph.roads.iter_mut().enumerate() {
            let text = HOSTILE[i % HOSTILE.len()];
            road.class = text.to_string();
            road.name = Some(text.to_string());
            road.provenance.sumo_ids.push(text.to_string());
        }
        for (i, junction) in graph.junctions.iter_mut().enumerate() {
            junction.provenance.sumo_ids = vec![HOSTILE[(i + 1) % HOSTILE.len()].to_string()];
        }
        graph.source.file = HOSTILE[0].to_string();
        let mut page = ViewPage::new(HOSTILE[3], &graph, &[]);
        page.subtitle = HOSTILE[2].to_string();
        page
    }

    #[test]
    fn map_text_stays_inside_the_data_block_and_reads_back_the_same() {
        let page = hostile_page();
        let html = page.html().unwrap();
        // the page has its own two scripts and nothing else: no map text opened or closed one
        assert_eq!(html.matches("<script").count(), 2, "{html}");
        assert_eq!(html.matches("</script>").count(), 2);
        assert_eq!(html.matches("<!--").count(), 0);
        let data = element_text(&html, "id=\"mapc-data\"");
        for c in ['<', '>', '&', '\u{2028}', '\u{2029}'] {
            assert!(!data.contains(c), "{c:?} in the embedded data");
        }
        // JSON.parse (serde_json here) gives back every string as the map had it
        let parsed: serde_json::Value = serde_json::from_str(data).unwrap();
        let direct: serde_json::Value = serde_json::from_str(&page.data_json().unwrap()).unwrap();
        assert_eq!(parsed, direct);
        for (i, road) in parsed["network"]["roads"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
        {
            assert_eq!(road["class"], HOSTILE[i % HOSTILE.len()]);
            assert_eq!(road["label"], HOSTILE[i % HOSTILE.len()]);
        }
        assert_eq!(parsed["title"], HOSTILE[3]);
        // the title is text, and a value that names a template marker is not filled in again
        assert_eq!(
            element_text(&html, "<title"),
            "&lt;/SCRIPT &gt;&amp;amp;{{DATA}}{{SCRIPT}}"
        );
        assert_eq!(html.matches(SCRIPT).count(), 1);
    }

    #[test]
    fn the_policy_names_exactly_the_pages_own_script_and_style() {
        let html = hostile_page().html().unwrap();
        let script = element_text(&html, "<script>");
        let style = element_text(&html, "<style>");
        assert_eq!(script, SCRIPT);
        assert_eq!(style, STYLE);
        let policy = content_security_policy(Delivery::File);
        assert!(
            html.contains(&format!(
                "<meta http-equiv=\"Content-Security-Policy\" content=\"{policy}\">"
            )),
            "the page carries its policy"
        );
        // the meta comes before anything it governs
        assert!(html.find("Content-Security-Policy").unwrap() < html.find("<style>").unwrap());
        assert!(policy.contains(&format!("script-src '{}';", hash_source(script))));
        assert!(policy.contains(&format!("style-src '{}';", hash_source(style))));
        for directive in [
            "default-src 'none'",
            "connect-src 'none'",
            "base-uri 'none'",
            "form-action 'none'",
            "require-trusted-types-for 'script'",
        ] {
            assert!(policy.contains(directive), "{policy} lacks {directive}");
        }
        assert!(!policy.contains("unsafe"), "{policy}");
        // served, it may fetch its data.json from where it came, and only that
        let served = content_security_policy(Delivery::Served);
        assert_eq!(
            served,
            policy.replace("connect-src 'none'", "connect-src 'self'")
        );
        assert!(crate::view::page_without_data("t").contains(&served));
        // a known vector: SHA-256 of "abc"
        assert_eq!(
            hash_source("abc"),
            "sha256-ungWv48Bz+pBQUDeXa4iI7ADYaOWF3qctBD/YfIAFa0="
        );
    }

    #[test]
    fn the_script_never_parses_html() {
        // the policy's Trusted Types would make such a line throw; this names it before a browser does
        for sink in [
            "innerHTML",
            "outerHTML",
            "insertAdjacentHTML",
            "document.write",
            "DOMParser",
            "createContextualFragment",
            "eval(",
            "new Function",
            "setAttribute(\"on",
        ] {
            assert!(!SCRIPT.contains(sink), "viewer.js uses {sink}");
        }
        assert!(!SCRIPT.contains("</script") && !STYLE.contains("</style"));
    }
}
