//! Text from a map written into XML (SVG pictures, SUMO files). A road's class, name or id is whatever the map's
//! author wrote, and may hold characters that XML 1.0 forbids anywhere in a document, even as a character
//! reference: the control characters but tab and the line breaks. One of them makes the whole file unreadable to
//! any XML parser. [`escape`] is the one escaping of such text; [`xml_safe`] alone serves a document a library
//! built, which escaped the markup characters itself.

use std::borrow::Cow;

/// Whether XML 1.0 allows `c` in a document (its `Char` production).
pub fn allowed_in_xml(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r' | '\u{20}'..='\u{d7ff}' | '\u{e000}'..='\u{fffd}' | '\u{10000}'..)
}

/// `text` with every character XML forbids written as `\uXXXX`, as the terminal shows it
/// ([`crate::terminal::printable`]).
pub fn xml_safe(text: &str) -> Cow<'_, str> {
    if text.chars().all(allowed_in_xml) {
        return Cow::Borrowed(text);
    }
    Cow::Owned(
        text.chars()
            .map(|c| {
                if allowed_in_xml(c) {
                    c.to_string()
                } else {
                    format!("\\u{:04x}", c as u32)
                }
            })
            .collect(),
    )
}

/// `text` for XML element content or a quoted attribute: the markup characters escaped and the forbidden ones
/// replaced ([`xml_safe`]).
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in xml_safe(text).chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_shown_and_markup_escaped() {
        assert_eq!(
            escape("ramp\u{1b}[31m\u{7}<&>\"'\tx\u{fffe}"),
            "ramp\\u001b[31m\\u0007&lt;&amp;&gt;&quot;&apos;\tx\\ufffe"
        );
        assert!(matches!(xml_safe("Süd → 荣乌\n"), Cow::Borrowed(_)));
    }
}
