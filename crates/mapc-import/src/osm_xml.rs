//! OSM XML, streamed in two passes so that memory holds only the kept ways and the nodes they use: the first pass
//! keeps the highway ways of the chosen classes and notes the node ids they name; the second reads just those
//! nodes' coordinates (checking every node's coordinates on the way).

use crate::error::ParseError;
use crate::osm::{NodePos, OsmData, OsmWay, WayTags, keeps, needed_nodes, parse_degrees};
use crate::xml::{Item, XmlStream, attrs, describe};
use std::collections::HashSet;
use std::io::BufRead;

/// What pass one found.
pub(crate) struct WaysPass {
    /// The kept ways (and the warnings about them); pass two adds the nodes.
    pub data: OsmData,
    /// True when every node came before the first way (the usual order), so pass two may stop at the first way.
    pub nodes_first: bool,
}

fn id_of(element: &quick_xml::events::BytesStart<'_>, at: u64) -> Result<i64, ParseError> {
    let raw = crate::xml::attr_value(element, "id")
        .map_err(|m| ParseError::new(at, Some(describe(element)), m))?;
    let Some(raw) = raw else {
        return Err(ParseError::new(at, Some(describe(element)), "missing `id`"));
    };
    raw.trim().parse().map_err(|_| {
        ParseError::new(
            at,
            Some(describe(element)),
            format!("id `{raw}` is not an integer"),
        )
    })
}

/// Pass one: the kept ways, in file order.
pub(crate) fn read_ways<R: BufRead>(input: R, classes: &[String]) -> Result<WaysPass, ParseError> {
    let mut xml = XmlStream::with_root(input, "osm", "OSM");
    let mut data = OsmData::default();
    let mut seen_way = false;
    let mut nodes_first = true;
    // The way being read: (id, nodes, tags) and where it starts, for errors.
    let mut current: Option<(i64, Vec<i64>, WayTags)> = None;
    let mut current_at = 0;
    let mut current_depth = 0;
    // The relation being read: (id, member ways, whether it is a turn restriction); those found.
    let mut relation: Option<(i64, Vec<i64>, bool)> = None;
    let mut restrictions: Vec<(i64, Vec<i64>)> = Vec::new();
    loop {
        match xml.next()? {
            Item::Eof => break,
            Item::Skip => {}
            Item::End => {
                if current.is_some() && xml.depth() < current_depth {
                    let (id, nodes, tags) = current.take().unwrap();
                    if keeps(classes, &tags) {
                        data.add_way(OsmWay { id, nodes, tags }).map_err(|m| {
                            ParseError::new(current_at, Some(format!("<way id=\"{id}\">")), m)
                        })?;
                    }
                }
                if relation.is_some() && xml.depth() < current_depth {
                    let (id, members, restriction) = relation.take().unwrap();
                    if restriction {
                        restrictions.push((id, members));
                    }
                }
            }
            Item::Start {
                element,
                empty,
                at,
                depth,
            } => {
                match element.name().as_ref() {
                    // a node after a way: the file is not in the usual nodes-first order
                    "node" => nodes_first &= !seen_way,
                    "way" => {
                        seen_way = true;
                        let id = id_of(&element, at)?;
                        if !empty {
                            current = Some((id, Vec::new(), WayTags::default()));
                            current_at = at;
                            current_depth = depth;
                        }
                    }
                    "relation" if !empty => {
                        relation = Some((id_of(&element, at)?, Vec::new(), false));
                        current_depth = depth;
                    }
                    "member" => {
                        if let Some((_, members, _)) = relation.as_mut() {
                            let kv = attrs(&element)
                                .map_err(|m| ParseError::new(at, Some(describe(&element)), m))?;
                            let get =
                                |key: &str| kv.iter().find(|(k, _)| *k == key).map(|(_, v)| v);
                            if get("type").is_some_and(|t| t == "way")
                                && let Some(Ok(r)) = get("ref").map(|r| r.trim().parse::<i64>())
                            {
                                members.push(r);
                            }
                        }
                    }
                    "nd" => {
                        if let Some((way_id, nodes, _)) = current.as_mut() {
                            let r = crate::xml::attr_value(&element, "ref")
                                .map_err(|m| {
                                    ParseError::new(at, Some(format!("<nd> of way {way_id}")), m)
                                })?
                                .ok_or_else(|| {
                                    ParseError::new(
                                        at,
                                        Some(format!("<nd> of way {way_id}")),
                                        "missing `ref`",
                                    )
                                })?;
                            let r: i64 = r.trim().parse().map_err(|_| {
                                ParseError::new(
                                    at,
                                    Some(format!("<nd> of way {way_id}")),
                                    format!("ref `{r}` is not an integer"),
                                )
                            })?;
                            nodes.push(r);
                        }
                    }
                    "tag" => {
                        if let Some((way_id, _, tags)) = current.as_mut() {
                            let kv = attrs(&element).map_err(|m| {
                                ParseError::new(at, Some(format!("<tag> of way {way_id}")), m)
                            })?;
                            let k = kv.iter().find(|(k, _)| *k == "k").map(|(_, v)| v.as_ref());
                            let v = kv.iter().find(|(k, _)| *k == "v").map(|(_, v)| v.as_ref());
                            if let (Some(k), Some(v)) = (k, v) {
                                tags.set(k, v);
                            }
                        } else if let Some((_, _, restriction)) = relation.as_mut() {
                            let kv = attrs(&element)
                                .map_err(|m| ParseError::new(at, Some(describe(&element)), m))?;
                            let get =
                                |key: &str| kv.iter().find(|(k, _)| *k == key).map(|(_, v)| v);
                            if get("k").is_some_and(|k| k == "type")
                                && get("v").is_some_and(|v| v.starts_with("restriction"))
                            {
                                *restriction = true;
                            }
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    data.note_restrictions(&restrictions);
    Ok(WaysPass { data, nodes_first })
}

/// Pass two: coordinates of the `needed` nodes. Every node's coordinates are checked, used or not.
pub(crate) fn read_nodes<R: BufRead>(
    input: R,
    needed: &HashSet<i64>,
    nodes_first: bool,
    data: &mut OsmData,
) -> Result<(), ParseError> {
    let mut xml = XmlStream::new(input);
    data.nodes.reserve(needed.len());
    loop {
        match xml.next()? {
            Item::Eof => break,
            Item::Skip => {}
            Item::End => {}
            Item::Start { element, at, .. } => match element.name().as_ref() {
                "node" => {
                    let (mut id, mut lat, mut lon) = (None, None, None);
                    let kv = attrs(&element)
                        .map_err(|m| ParseError::new(at, Some(describe(&element)), m))?;
                    for (k, v) in kv {
                        match k {
                            "id" => id = Some(v),
                            "lat" => lat = Some(v),
                            "lon" => lon = Some(v),
                            _ => {}
                        }
                    }
                    let el = || Some(describe(&element));
                    let id: i64 = match id {
                        Some(v) => v.trim().parse().map_err(|_| {
                            ParseError::new(at, el(), format!("id `{v}` is not an integer"))
                        })?,
                        None => return Err(ParseError::new(at, el(), "missing `id`")),
                    };
                    let lat = lat.ok_or_else(|| ParseError::new(at, el(), "missing `lat`"))?;
                    let lon = lon.ok_or_else(|| ParseError::new(at, el(), "missing `lon`"))?;
                    let lat_e7 = parse_degrees(&lat, 90.0)
                        .map_err(|m| ParseError::new(at, el(), format!("lat: {m}")))?;
                    let lon_e7 = parse_degrees(&lon, 180.0)
                        .map_err(|m| ParseError::new(at, el(), format!("lon: {m}")))?;
                    if needed.contains(&id) {
                        data.add_node(id, NodePos { lat_e7, lon_e7 })
                            .map_err(|m| ParseError::new(at, el(), m))?;
                    }
                }
                "way" | "relation" if nodes_first => break,
                _ => {}
            },
        }
    }
    Ok(())
}

/// Both passes over a re-openable input.
pub(crate) fn read<R: BufRead>(
    mut open: impl FnMut() -> Result<R, ParseError>,
    classes: &[String],
) -> Result<OsmData, ParseError> {
    let mut pass = read_ways(open()?, classes)?;
    let needed = needed_nodes(&pass.data.ways);
    read_nodes(open()?, &needed, pass.nodes_first, &mut pass.data)?;
    Ok(pass.data)
}
