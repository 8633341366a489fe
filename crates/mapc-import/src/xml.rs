//! A thin streaming layer over quick-xml shared by the OSM and SUMO readers: events with byte offsets, open-element
//! tracking (so a truncated file is an error, not a short map) and attribute helpers.

use crate::error::ParseError;
use quick_xml::events::{BytesStart, Event};
use quick_xml::{Reader, XmlVersion};
use std::borrow::Cow;
use std::io::BufRead;

pub(crate) struct XmlStream<R: BufRead> {
    reader: Reader<R>,
    buf: Vec<u8>,
    /// Names of the open elements, outermost first.
    open: Vec<String>,
    /// Byte offset where the last event returned began.
    pub start: u64,
    pub root: Option<String>,
    /// The root element a reader expects and what the file is then, for the error when it is another.
    expected_root: Option<(&'static str, &'static str)>,
}

/// One element start (`<a ..>` or `<a ../>`), an element end, or the end of the input.
pub(crate) enum Item<'b> {
    /// `at`: byte offset of the `<`; `depth`: 1 for the root.
    Start {
        element: BytesStart<'b>,
        empty: bool,
        at: u64,
        depth: usize,
    },
    End,
    /// Text, a comment, a declaration: nothing a reader needs.
    Skip,
    Eof,
}

impl<R: BufRead> XmlStream<R> {
    pub fn new(input: R) -> Self {
        let mut reader = Reader::from_reader(input);
        let config = reader.config_mut();
        config.check_end_names = true;
        config.trim_text_start = false;
        XmlStream {
            reader,
            buf: Vec::with_capacity(4096),
            open: Vec::new(),
            start: 0,
            root: None,
            expected_root: None,
        }
    }

    /// A stream of a file whose root element must be `<root>` (`what` says what such a file is: "OSM", "a SUMO
    /// network"): another root is an error naming both; the root's own start comes back as [`Item::Skip`].
    pub fn with_root(input: R, root: &'static str, what: &'static str) -> Self {
        XmlStream {
            expected_root: Some((root, what)),
            ..XmlStream::new(input)
        }
    }

    /// Depth of the element the last `Start` opened (1 for the root), or of the current parent after an `End`.
    pub fn depth(&self) -> usize {
        self.open.len()
    }

    /// Next event; text, comments and declarations come back as [`Item::Skip`].
    pub fn next(&mut self) -> Result<Item<'_>, ParseError> {
        {
            self.buf.clear();
            self.start = self.reader.buffer_position();
            let event = match self.reader.read_event_into(&mut self.buf) {
                Ok(e) => e,
                Err(e) => {
                    let at = self.reader.error_position().max(self.start);
                    return Err(ParseError::new(
                        at,
                        self.open.last().map(|n| format!("<{n}>")),
                        match e {
                            quick_xml::Error::Syntax(_) => {
                                format!(
                                    "not well-formed XML: {e} (the file ends too early: truncated?)"
                                )
                            }
                            _ => format!("not well-formed XML: {e}"),
                        },
                    ));
                }
            };
            match event {
                Event::Start(_) | Event::Empty(_) => {
                    let empty = matches!(event, Event::Empty(_));
                    let (Event::Start(element) | Event::Empty(element)) = event else {
                        unreachable!()
                    };
                    if self.open.is_empty() && self.root.is_some() {
                        return Err(ParseError::new(
                            self.start,
                            None,
                            "more than one root element",
                        ));
                    }
                    let name = element.name().as_ref().to_string();
                    let is_root = self.root.is_none();
                    if is_root {
                        self.root = Some(name.clone());
                    }
                    if is_root && let Some((root, what)) = self.expected_root {
                        if name != root {
                            return Err(ParseError::new(
                                self.start,
                                Some(format!("<{name}>")),
                                format!(
                                    "this is XML but not {what} (root element <{name}>, expected <{root}>)"
                                ),
                            ));
                        }
                        if !empty {
                            self.open.push(name);
                        }
                        return Ok(Item::Skip);
                    }
                    if !empty {
                        self.open.push(name);
                    }
                    let (at, depth) = (self.start, self.open.len() + usize::from(empty));
                    return Ok(Item::Start {
                        element,
                        empty,
                        at,
                        depth,
                    });
                }
                Event::End(_) => {
                    self.open.pop();
                    return Ok(Item::End);
                }
                Event::Eof => {
                    if let Some(open) = self.open.last() {
                        return Err(ParseError::new(
                            self.start,
                            Some(format!("<{open}>")),
                            format!("the file ends inside <{open}> (truncated?)"),
                        ));
                    }
                    if self.root.is_none() {
                        return Err(ParseError::new(
                            self.start,
                            None,
                            "no XML element in the file",
                        ));
                    }
                    return Ok(Item::Eof);
                }
                Event::Text(t) if self.open.is_empty() && !t.trim_ascii().is_empty() => {
                    return Err(ParseError::new(
                        self.start,
                        None,
                        "text outside the root element: not an XML file",
                    ));
                }
                _ => {}
            }
            Ok(Item::Skip)
        }
    }
}

/// Attribute value as text with XML entities (`&amp;`) resolved.
pub(crate) fn attr_value<'a>(
    element: &'a BytesStart<'_>,
    key: &str,
) -> Result<Option<Cow<'a, str>>, String> {
    for a in element.attributes() {
        let a = a.map_err(|e| format!("bad attribute: {e}"))?;
        if a.key.as_ref() == key {
            return a
                .normalized_value(XmlVersion::Implicit1_0)
                .map(Some)
                .map_err(|e| format!("attribute `{key}`: {e}"));
        }
    }
    Ok(None)
}

/// All attributes as (key, raw value) pairs; values with `&` are resolved.
pub(crate) fn attrs<'a>(
    element: &'a BytesStart<'_>,
) -> Result<Vec<(&'a str, Cow<'a, str>)>, String> {
    let mut out = Vec::with_capacity(8);
    for a in element.attributes() {
        let a = a.map_err(|e| format!("bad attribute: {e}"))?;
        let key: &'a str = a.key.0;
        let value = if a.value.contains('&') {
            Cow::Owned(
                a.normalized_value(XmlVersion::Implicit1_0)
                    .map_err(|e| format!("attribute `{key}`: {e}"))?
                    .into_owned(),
            )
        } else {
            a.value
        };
        out.push((key, value));
    }
    Ok(out)
}

/// `<name k="v" ..>` for error messages: the element with its id, if any.
pub(crate) fn describe(element: &BytesStart<'_>) -> String {
    let name = element.name().as_ref().to_string();
    match attr_value(element, "id") {
        Ok(Some(id)) => format!("<{name} id=\"{id}\">"),
        _ => format!("<{name}>"),
    }
}
