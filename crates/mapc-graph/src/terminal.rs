//! Text for the terminal. Maps come from the internet, and a road's name, class or id is whatever its author wrote:
//! an escape sequence in it would retitle the window, clear the screen or rewrite earlier lines when printed, and a
//! bidirectional override would show one id as another. Every line the binary prints passes through
//! [`printable`] (by the `println!` and `eprintln!` of its `main.rs` that shadow the standard ones), and so does
//! the message of every error the Python package raises.

use std::borrow::Cow;

/// `text` with every character that steers a terminal written as `\uXXXX`: control characters but the line break
/// (C0, DEL, C1) and the invisible format characters that reorder or hide text (bidirectional embeddings,
/// overrides and isolates, zero-width characters, the byte-order mark). `\uXXXX` is also JSON's escape, so a JSON
/// document printed through this stays valid and means the same.
pub fn printable(text: &str) -> Cow<'_, str> {
    if !text.chars().any(steers_terminal) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        if steers_terminal(c) {
            out.push_str(&format!("\\u{:04x}", c as u32));
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

/// A number as a message shows it: plain when short, else in exponent form (`1e308`, not 309 digits).
pub fn number(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

fn steers_terminal(c: char) -> bool {
    (c.is_control() && c != '\n')
        || matches!(c, '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2060}'..='\u{2069}' | '\u{feff}')
}

#[cfg(test)]
mod tests {
    use super::printable;

    #[test]
    fn escape_sequences_and_overrides_are_shown_not_obeyed() {
        let hostile = "merge\u{1b}]0;pwned\u{7}\u{1b}[2J\u{9b}31m\u{202e}ramp\r\tx";
        assert_eq!(
            printable(hostile),
            "merge\\u001b]0;pwned\\u0007\\u001b[2J\\u009b31m\\u202eramp\\u000d\\u0009x"
        );
    }

    #[test]
    fn plain_text_line_breaks_and_other_scripts_pass_unchanged() {
        for text in [
            "J43 (osm:61862553)\n  lanes: R86 3",
            "荣乌高速",
            "Auf der Autobahn → Süd",
            "",
        ] {
            assert!(matches!(printable(text), std::borrow::Cow::Borrowed(t) if t == text));
        }
    }

    #[test]
    fn json_stays_valid_and_means_the_same() {
        let value = serde_json::json!({ "name": "a\u{9b}b\u{202e}c\u{1b}" });
        let printed = printable(&serde_json::to_string(&value).unwrap()).into_owned();
        assert!(!printed.chars().any(|c| c.is_control()));
        assert_eq!(
            serde_json::from_str::<serde_json::Value>(&printed).unwrap(),
            value
        );
    }
}
