//! OSM PBF: the blob framing, decompression and block decoding are done here (with osmpbfreader's generated
//! protobuf types) so that every size, index and delta is checked: a corrupt or truncated file is an error naming
//! the byte offset and blob, never a panic. Two passes over the blobs, as for XML: kept ways first, then only the
//! nodes they use.

use crate::error::ParseError;
use crate::osm::{NodePos, OsmData, OsmWay, WayTags, keeps, needed_nodes};
use osmpbfreader::fileformat::{Blob, BlobHeader};
use osmpbfreader::osmformat::{HeaderBlock, PrimitiveBlock};
use protobuf::Message;
use std::collections::HashSet;
use std::io::Read;

/// The format's own limits: a blob header under 64 KiB, a blob under 32 MiB.
const MAX_HEADER: usize = 64 * 1024;
const MAX_BLOB: usize = 32 * 1024 * 1024;
/// Features of the format this reader understands.
const KNOWN_FEATURES: [&str; 3] = ["OsmSchema-V0.6", "DenseNodes", "HistoricalInformation"];

/// One data blob's place in the file.
struct BlobAt {
    index: usize,
    offset: u64,
    kind: String,
    data: std::ops::Range<usize>,
}

fn err(offset: u64, index: usize, message: impl Into<String>) -> ParseError {
    ParseError::new(offset, Some(format!("blob {index}")), message)
}

/// Split the file into blobs, checking the framing.
fn frame(bytes: &[u8]) -> Result<Vec<BlobAt>, ParseError> {
    let mut out = Vec::new();
    let mut pos = 0usize;
    let mut index = 0;
    while pos < bytes.len() {
        let offset = pos as u64;
        let Some(len_bytes) = bytes.get(pos..pos + 4) else {
            return Err(err(
                offset,
                index,
                "the file ends inside a blob's length (truncated?)",
            ));
        };
        let header_len = u32::from_be_bytes(len_bytes.try_into().expect("4 bytes")) as usize;
        if header_len == 0 || header_len > MAX_HEADER {
            return Err(err(
                offset,
                index,
                format!(
                    "blob header length {header_len} is not 1..{MAX_HEADER}: not an OSM PBF file, or corrupt"
                ),
            ));
        }
        pos += 4;
        let Some(header_bytes) = bytes.get(pos..pos + header_len) else {
            return Err(err(
                offset,
                index,
                "the file ends inside a blob header (truncated?)",
            ));
        };
        let header = BlobHeader::parse_from_bytes(header_bytes)
            .map_err(|e| err(offset, index, format!("bad blob header: {e}")))?;
        pos += header_len;
        let size = header.datasize();
        if size < 0 || size as usize > MAX_BLOB {
            return Err(err(
                offset,
                index,
                format!("blob size {size} is not 0..{MAX_BLOB}"),
            ));
        }
        let size = size as usize;
        if pos + size > bytes.len() {
            return Err(err(
                offset,
                index,
                format!("the file ends inside a blob of {size} bytes (truncated?)"),
            ));
        }
        if index == 0 && header.type_() != "OSMHeader" {
            return Err(err(
                offset,
                index,
                format!(
                    "first blob is `{}`, not `OSMHeader`: not an OSM PBF file",
                    header.type_()
                ),
            ));
        }
        out.push(BlobAt {
            index,
            offset,
            kind: header.type_().to_string(),
            data: pos..pos + size,
        });
        pos += size;
        index += 1;
    }
    if out.is_empty() {
        return Err(err(0, 0, "no blobs: not an OSM PBF file"));
    }
    Ok(out)
}

/// The uncompressed content of a blob.
fn unpack(bytes: &[u8], at: &BlobAt) -> Result<Vec<u8>, ParseError> {
    let blob = Blob::parse_from_bytes(&bytes[at.data.clone()])
        .map_err(|e| err(at.offset, at.index, format!("bad blob: {e}")))?;
    if blob.has_raw() {
        return Ok(blob.raw().to_vec());
    }
    if blob.has_zlib_data() {
        let raw_size = blob.raw_size();
        if raw_size < 0 || raw_size as usize > MAX_BLOB {
            return Err(err(
                at.offset,
                at.index,
                format!("uncompressed size {raw_size} is not 0..{MAX_BLOB}"),
            ));
        }
        let mut out = Vec::with_capacity(raw_size as usize);
        flate2::read::ZlibDecoder::new(blob.zlib_data())
            .take(MAX_BLOB as u64 + 1)
            .read_to_end(&mut out)
            .map_err(|e| err(at.offset, at.index, format!("corrupt zlib data: {e}")))?;
        if out.len() != raw_size as usize {
            return Err(err(
                at.offset,
                at.index,
                format!(
                    "unpacked to {} bytes, the header says {raw_size}",
                    out.len()
                ),
            ));
        }
        return Ok(out);
    }
    Err(err(
        at.offset,
        at.index,
        "blob compression not supported (mapc reads raw and zlib blobs)",
    ))
}

fn check_header(bytes: &[u8], at: &BlobAt) -> Result<(), ParseError> {
    let data = unpack(bytes, at)?;
    let header = HeaderBlock::parse_from_bytes(&data)
        .map_err(|e| err(at.offset, at.index, format!("bad header block: {e}")))?;
    for f in &header.required_features {
        if !KNOWN_FEATURES.contains(&f.as_str()) {
            return Err(err(
                at.offset,
                at.index,
                format!("the file requires the feature `{f}`, which mapc does not read"),
            ));
        }
    }
    Ok(())
}

fn block(bytes: &[u8], at: &BlobAt) -> Result<PrimitiveBlock, ParseError> {
    let data = unpack(bytes, at)?;
    PrimitiveBlock::parse_from_bytes(&data)
        .map_err(|e| err(at.offset, at.index, format!("bad data block: {e}")))
}

fn string<'a>(b: &'a PrimitiveBlock, i: u32, at: &BlobAt) -> Result<&'a [u8], ParseError> {
    b.stringtable
        .s
        .get(i as usize)
        .map(Vec::as_slice)
        .ok_or_else(|| {
            err(
                at.offset,
                at.index,
                format!("string index {i} outside the block's table"),
            )
        })
}

/// Coordinate in 1e-7 degree: offset + granularity * value nanodegrees, checked.
fn coordinate(
    offset: i64,
    granularity: i32,
    value: i64,
    limit: i64,
    at: &BlobAt,
    what: &str,
    id: i64,
) -> Result<i32, ParseError> {
    let nano = (granularity as i128) * (value as i128) + offset as i128;
    let e7 = nano / 100;
    if e7.abs() > (limit * 10_000_000) as i128 {
        return Err(err(
            at.offset,
            at.index,
            format!("node {id}: {what} {} is out of range", e7 as f64 * 1e-7),
        ));
    }
    Ok(e7 as i32)
}

fn read_ways(bytes: &[u8], blobs: &[BlobAt], classes: &[String]) -> Result<OsmData, ParseError> {
    let mut data = OsmData::default();
    let mut restrictions: Vec<(i64, Vec<i64>)> = Vec::new();
    for at in blobs.iter().filter(|b| b.kind == "OSMData") {
        let b = block(bytes, at)?;
        for g in &b.primitivegroup {
            for r in &g.relations {
                let mut restriction = false;
                for (&k, &v) in r.keys.iter().zip(&r.vals) {
                    if string(&b, k, at)? == b"type"
                        && string(&b, v, at)?.starts_with(b"restriction")
                    {
                        restriction = true;
                    }
                }
                if !restriction {
                    continue;
                }
                // member ids are delta-coded; type 1 is a way
                let mut id = 0i64;
                let mut members = Vec::new();
                for (i, &delta) in r.memids.iter().enumerate() {
                    id = id.wrapping_add(delta);
                    if r.types.get(i).is_some_and(|t| t.value() == 1) {
                        members.push(id);
                    }
                }
                restrictions.push((r.id(), members));
            }
            for w in &g.ways {
                if w.keys.len() != w.vals.len() {
                    return Err(err(
                        at.offset,
                        at.index,
                        format!(
                            "way {}: {} keys but {} values",
                            w.id(),
                            w.keys.len(),
                            w.vals.len()
                        ),
                    ));
                }
                let mut tags = WayTags::default();
                for (&k, &v) in w.keys.iter().zip(&w.vals) {
                    let k = String::from_utf8_lossy(string(&b, k, at)?);
                    let v = String::from_utf8_lossy(string(&b, v, at)?);
                    tags.set(&k, &v);
                }
                if !keeps(classes, &tags) {
                    continue;
                }
                let mut id = 0i64;
                let mut nodes = Vec::with_capacity(w.refs.len());
                for &delta in &w.refs {
                    id = id.checked_add(delta).ok_or_else(|| {
                        err(
                            at.offset,
                            at.index,
                            format!("way {}: node id overflows", w.id()),
                        )
                    })?;
                    nodes.push(id);
                }
                data.add_way(OsmWay {
                    id: w.id(),
                    nodes,
                    tags,
                })
                .map_err(|m| err(at.offset, at.index, m))?;
            }
        }
    }
    data.note_restrictions(&restrictions);
    Ok(data)
}

fn read_nodes(
    bytes: &[u8],
    blobs: &[BlobAt],
    needed: &HashSet<i64>,
    data: &mut OsmData,
) -> Result<(), ParseError> {
    data.nodes.reserve(needed.len());
    for at in blobs.iter().filter(|b| b.kind == "OSMData") {
        let b = block(bytes, at)?;
        let (gran, lat_off, lon_off) = (b.granularity(), b.lat_offset(), b.lon_offset());
        if gran <= 0 {
            return Err(err(
                at.offset,
                at.index,
                format!("granularity {gran} is not positive"),
            ));
        }
        let mut keep = |id: i64, lat: i64, lon: i64| -> Result<(), ParseError> {
            let lat_e7 = coordinate(lat_off, gran, lat, 90, at, "latitude", id)?;
            let lon_e7 = coordinate(lon_off, gran, lon, 180, at, "longitude", id)?;
            if needed.contains(&id) {
                data.add_node(id, NodePos { lat_e7, lon_e7 })
                    .map_err(|m| err(at.offset, at.index, m))?;
            }
            Ok(())
        };
        for g in &b.primitivegroup {
            for n in &g.nodes {
                keep(n.id(), n.lat(), n.lon())?;
            }
            if let Some(d) = g.dense.as_ref() {
                if d.id.len() != d.lat.len() || d.id.len() != d.lon.len() {
                    return Err(err(
                        at.offset,
                        at.index,
                        "dense nodes: ids, latitudes and longitudes differ in number",
                    ));
                }
                let (mut id, mut lat, mut lon) = (0i64, 0i64, 0i64);
                for i in 0..d.id.len() {
                    let overflow = || err(at.offset, at.index, "dense nodes: a delta overflows");
                    id = id.checked_add(d.id[i]).ok_or_else(overflow)?;
                    lat = lat.checked_add(d.lat[i]).ok_or_else(overflow)?;
                    lon = lon.checked_add(d.lon[i]).ok_or_else(overflow)?;
                    keep(id, lat, lon)?;
                }
            }
        }
    }
    Ok(())
}

/// Both passes over a PBF file held in memory (it is compressed: a tenth of the XML's size).
pub(crate) fn read(bytes: &[u8], classes: &[String]) -> Result<OsmData, ParseError> {
    let blobs = frame(bytes)?;
    check_header(bytes, &blobs[0])?;
    let mut data = read_ways(bytes, &blobs, classes)?;
    let needed = needed_nodes(&data.ways);
    read_nodes(bytes, &blobs, &needed, &mut data)?;
    Ok(data)
}
