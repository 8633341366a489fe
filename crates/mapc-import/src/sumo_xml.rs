//! SUMO's other XML inputs (configurations, route and additional files) read as a tree of elements, each with its
//! attributes and its place in the file (`FILE: line L, column C, in <flow id="f1">`), so that whoever interprets
//! them can name the place of every value it refuses. Only the structure is checked here: well-formed XML and
//! the expected root element.

use crate::error::{ImportError, Located, ParseError, line_and_column};
use crate::xml::{Item, XmlStream, attrs, describe};
use std::path::Path;

/// One element of a SUMO XML file.
#[derive(Clone, Debug, PartialEq)]
pub struct SumoElement {
    /// The element's name (`flow`, `vType`, ...).
    pub name: String,
    /// Its attributes in file order, entities resolved.
    pub attrs: Vec<(String, String)>,
    /// Where it is, for messages: `FILE: line L, column C, in <flow id="f1">`.
    pub place: String,
    pub children: Vec<SumoElement>,
}

impl SumoElement {
    /// The value of attribute `key`, if given.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// Attribute `key` as a finite number, if given; the message when it is not one.
    pub fn number(&self, key: &str) -> Result<Option<f64>, String> {
        number_attr(key, self.get(key))
    }
}

/// An attribute's text as a finite number (`None` when absent), or the message naming the attribute and its text.
pub(crate) fn number_attr(key: &str, text: Option<&str>) -> Result<Option<f64>, String> {
    match text {
        None => Ok(None),
        Some(v) => v
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .map(Some)
            .ok_or_else(|| format!("`{key}` is `{v}`, not a number")),
    }
}

/// A boolean as SUMO's options and attributes spell it (`None`: not one).
pub fn sumo_bool(value: &str) -> Option<bool> {
    match value.trim() {
        "true" | "1" | "on" | "yes" | "x" => Some(true),
        "false" | "0" | "off" | "no" | "" => Some(false),
        _ => None,
    }
}

/// Read `path`, a SUMO XML file whose root element is one of `roots` (`what` names such a file in errors:
/// "a SUMO route file"). The root comes back with the whole file below it.
pub fn read_sumo_xml(path: &Path, roots: &[&str], what: &str) -> Result<SumoElement, ImportError> {
    let bytes = crate::gz::read_input(path).map_err(|e| ImportError::io(path, e))?;
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(ImportError::Empty {
            path: path.to_path_buf(),
        });
    }
    let located = Located::Bytes(path, &bytes);
    parse(&bytes, path, roots, what).map_err(|e| located.error(e))
}

fn parse(bytes: &[u8], path: &Path, roots: &[&str], what: &str) -> Result<SumoElement, ParseError> {
    let mut xml = XmlStream::new(bytes);
    // the open elements, outermost first; the root at 0
    let mut stack: Vec<SumoElement> = Vec::new();
    let mut done: Option<SumoElement> = None;
    let mut lines = LineCounter::default();
    loop {
        match xml.next()? {
            Item::Eof => break,
            Item::Skip => {}
            Item::Start {
                element, empty, at, ..
            } => {
                let described = describe(&element);
                let name = element.name().as_ref().to_string();
                let kv = attrs(&element)
                    .map_err(|m| ParseError::new(at, Some(described.clone()), m))?
                    .into_iter()
                    .map(|(k, v)| (k.to_string(), v.into_owned()))
                    .collect();
                if stack.is_empty() && !roots.contains(&name.as_str()) {
                    return Err(ParseError::new(
                        at,
                        Some(described),
                        format!(
                            "this is XML but not {what} (root element <{name}>, expected <{}>)",
                            roots.join("> or <")
                        ),
                    ));
                }
                let (line, column) = lines.at(bytes, at);
                let e = SumoElement {
                    name,
                    attrs: kv,
                    place: format!(
                        "{}: line {line}, column {column}, in {described}",
                        path.display()
                    ),
                    children: Vec::new(),
                };
                if empty {
                    match stack.last_mut() {
                        Some(parent) => parent.children.push(e),
                        None => done = Some(e),
                    }
                } else {
                    stack.push(e);
                }
            }
            Item::End => {
                let e = stack
                    .pop()
                    .expect("the stream matches every end with a start");
                match stack.last_mut() {
                    Some(parent) => parent.children.push(e),
                    None => done = Some(e),
                }
            }
        }
    }
    done.ok_or_else(|| ParseError::new(0, None, "no XML element in the file"))
}

/// Lines and columns of byte offsets met in increasing order, counted from the last one: a file's every element
/// names its place, and counting from the file's start each time made reading quadratic in its length (a 190 KB
/// network took 0.3 s).
#[derive(Default)]
struct LineCounter {
    offset: usize,
    line: usize,
    line_start: usize,
}

impl LineCounter {
    fn at(&mut self, text: &[u8], byte: u64) -> (usize, usize) {
        let end = (byte as usize).min(text.len());
        if end < self.offset {
            return line_and_column(text, byte);
        }
        for (i, &b) in text[self.offset..end].iter().enumerate() {
            if b == b'\n' {
                self.line += 1;
                self.line_start = self.offset + i + 1;
            }
        }
        self.offset = end;
        (self.line + 1, end - self.line_start + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_counted_from_the_last_place_match_lines_counted_from_the_start() {
        let text = b"<a>\n  <b/>\r\n\n<c x=\"1\"/>\n</a>\n";
        let mut lines = LineCounter::default();
        for at in [0u64, 2, 3, 6, 9, 10, 12, 13, 20, 5, 40] {
            assert_eq!(lines.at(text, at), line_and_column(text, at), "byte {at}");
        }
    }

    fn read(text: &str) -> Result<SumoElement, String> {
        let dir = std::env::temp_dir().join(format!("mapc_sumo_xml_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(format!("t{}.rou.xml", text.len()));
        std::fs::write(&p, text).unwrap();
        read_sumo_xml(&p, &["routes"], "a SUMO route file").map_err(|e| e.to_string())
    }

    #[test]
    fn elements_keep_their_attributes_children_and_places() {
        let r = read("<routes>\n  <vType id=\"car\" accel=\"2.6\"/>\n  <flow id=\"f\" from=\"a\">\n    <param key=\"k\" value=\"v\"/>\n  </flow>\n</routes>\n").unwrap();
        assert_eq!(r.name, "routes");
        assert_eq!(r.children.len(), 2);
        assert_eq!(r.children[0].get("accel"), Some("2.6"));
        assert!(
            r.children[0]
                .place
                .contains("line 2, column 3, in <vType id=\"car\">"),
            "{}",
            r.children[0].place
        );
        assert_eq!(r.children[1].children[0].name, "param");
        assert!(r.children[1].children[0].place.contains("line 4"));
    }

    #[test]
    fn another_root_or_broken_xml_is_refused_with_its_place() {
        let e = read("<net>\n</net>").unwrap_err();
        assert!(
            e.contains("not a SUMO route file") && e.contains("line 1"),
            "{e}"
        );
        let e = read("<routes>\n<flow id=\"f\">\n</routes>").unwrap_err();
        assert!(e.contains("line 3"), "{e}");
        let e = read("<routes>\n<vType id=\"a\"/>\n").unwrap_err();
        assert!(e.contains("truncated"), "{e}");
    }
}
