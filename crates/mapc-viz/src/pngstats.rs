//! Reading back a PNG this crate wrote, to check a picture has content: its size, how many colours it uses and how
//! much of it is not white. Reads 8-bit RGB and RGBA, not interlaced (what the bitmap backend writes).

use crate::VizError;
use serde::Serialize;
use std::collections::HashSet;
use std::io::Read;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, Serialize)]
pub struct PngStats {
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    /// Distinct colours (counted up to 100 000).
    pub colors: usize,
    /// Share of pixels that are not white.
    pub ink_fraction: f64,
}

/// How many pixels are close to `rgb` (within `tol` on each channel).
pub fn count_near(pixels: &[[u8; 3]], rgb: [u8; 3], tol: u8) -> usize {
    pixels
        .iter()
        .filter(|p| p.iter().zip(rgb).all(|(a, b)| a.abs_diff(b) <= tol))
        .count()
}

const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

/// The statistics and the RGB pixels of a PNG file.
pub fn read_png(path: &Path) -> Result<(PngStats, Vec<[u8; 3]>), VizError> {
    let bad = |message: &str| VizError::Input {
        path: path.to_path_buf(),
        message: message.to_string(),
    };
    let bytes = mapc_graph::input::read(path).map_err(|source| VizError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if bytes.len() < 33 || bytes[..8] != SIGNATURE {
        return Err(bad("not a PNG file (no PNG signature)"));
    }
    let (mut width, mut height, mut channels) = (0u32, 0u32, 0usize);
    let mut idat = Vec::new();
    let mut at = 8;
    while at + 8 <= bytes.len() {
        let len = u32::from_be_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as usize;
        let kind = &bytes[at + 4..at + 8];
        let body = bytes
            .get(at + 8..at + 8 + len)
            .ok_or_else(|| bad("truncated PNG chunk"))?;
        match kind {
            b"IHDR" => {
                if body.len() < 13 {
                    return Err(bad("short IHDR chunk"));
                }
                width = u32::from_be_bytes(body[0..4].try_into().expect("4 bytes"));
                height = u32::from_be_bytes(body[4..8].try_into().expect("4 bytes"));
                let (depth, color, interlace) = (body[8], body[9], body[12]);
                channels = match (depth, color, interlace) {
                    (8, 2, 0) => 3,
                    (8, 6, 0) => 4,
                    _ => return Err(bad("only 8-bit RGB/RGBA, non-interlaced PNGs are read")),
                };
            }
            b"IDAT" => idat.extend_from_slice(body),
            b"IEND" => break,
            _ => {}
        }
        at += 12 + len;
    }
    if channels == 0 || width == 0 || height == 0 {
        return Err(bad("PNG without a usable header"));
    }
    let mut raw = Vec::new();
    flate2::read::ZlibDecoder::new(&idat[..])
        .read_to_end(&mut raw)
        .map_err(|e| bad(&format!("bad image data: {e}")))?;
    let stride = width as usize * channels;
    if raw.len() < (stride + 1) * height as usize {
        return Err(bad("image data shorter than the header says"));
    }
    let mut pixels = Vec::with_capacity(width as usize * height as usize);
    let mut prev = vec![0u8; stride];
    let mut cur = vec![0u8; stride];
    for row in 0..height as usize {
        let line = &raw[row * (stride + 1)..(row + 1) * (stride + 1)];
        let filter = line[0];
        for i in 0..stride {
            let x = line[1 + i];
            let a = if i >= channels { cur[i - channels] } else { 0 };
            let b = prev[i];
            let c = if i >= channels { prev[i - channels] } else { 0 };
            cur[i] = match filter {
                0 => x,
                1 => x.wrapping_add(a),
                2 => x.wrapping_add(b),
                3 => x.wrapping_add(((a as u16 + b as u16) / 2) as u8),
                4 => x.wrapping_add(paeth(a, b, c)),
                _ => return Err(bad("unknown PNG row filter")),
            };
        }
        pixels.extend(cur.chunks(channels).map(|p| [p[0], p[1], p[2]]));
        std::mem::swap(&mut prev, &mut cur);
    }
    let mut colors = HashSet::new();
    let mut ink = 0usize;
    for p in &pixels {
        if colors.len() < 100_000 {
            colors.insert(*p);
        }
        if *p != [255, 255, 255] {
            ink += 1;
        }
    }
    let stats = PngStats {
        path: path.to_path_buf(),
        width,
        height,
        colors: colors.len(),
        ink_fraction: ink as f64 / pixels.len() as f64,
    };
    Ok((stats, pixels))
}

fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let p = a as i16 + b as i16 - c as i16;
    let (pa, pb, pc) = (
        (p - a as i16).abs(),
        (p - b as i16).abs(),
        (p - c as i16).abs(),
    );
    if pa <= pb && pa <= pc {
        a
    } else if pb <= pc {
        b
    } else {
        c
    }
}
