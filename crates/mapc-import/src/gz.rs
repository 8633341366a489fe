//! Gzip-compressed XML inputs: SUMO reads any of its XML inputs compressed (a `.net.xml.gz`, a `.rou.xml.gz`), and
//! so does mapc. A compressed file is told by its first two bytes, whatever its name, and decompressed under the
//! same cap as any input ([`mapc_graph::input`]): the cap bounds what comes out, not the file.

use std::io::Read;
use std::path::{Path, PathBuf};

/// Gzip's first two bytes.
const MAGIC: [u8; 2] = [0x1f, 0x8b];

/// Whether bytes starting with `head` are gzip-compressed.
pub fn is_gzip(head: &[u8]) -> bool {
    head.starts_with(&MAGIC)
}

/// The whole of `path`'s content: decompressed when the file is gzip, as it is otherwise.
pub fn read_input(path: &Path) -> std::io::Result<Vec<u8>> {
    let bytes = mapc_graph::input::read(path)?;
    if !is_gzip(&bytes) {
        return Ok(bytes);
    }
    let mut out = Vec::new();
    mapc_graph::input::capped(flate2::read::MultiGzDecoder::new(&bytes[..]))?
        .read_to_end(&mut out)
        .map_err(|e| std::io::Error::new(e.kind(), format!("gzip-compressed, but {e}")))?;
    Ok(out)
}

/// The first bytes of `path`'s content (up to [`mapc_graph::filekind::HEAD_BYTES`]), decompressed when the file is
/// gzip; and whether it is.
pub(crate) fn read_head(path: &Path) -> std::io::Result<(Vec<u8>, bool)> {
    let head = mapc_graph::filekind::read_head(path)?;
    if !is_gzip(&head) {
        return Ok((head, false));
    }
    let mut out = Vec::new();
    // (a corrupt stream's head is whatever came out before the fault: the full read reports it)
    let _ = flate2::read::MultiGzDecoder::new(mapc_graph::input::open(path)?)
        .take(mapc_graph::filekind::HEAD_BYTES as u64)
        .read_to_end(&mut out);
    Ok((out, true))
}

/// `path` without a final `.gz`: the name that tells a compressed file's format.
pub(crate) fn inner_name(path: &Path) -> PathBuf {
    match path.file_name().and_then(|n| n.to_str()) {
        Some(n) if n.to_ascii_lowercase().ends_with(".gz") => {
            path.with_file_name(&n[..n.len() - 3])
        }
        _ => path.to_path_buf(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn compressed(bytes: &[u8]) -> Vec<u8> {
        let mut z = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(bytes).unwrap();
        z.finish().unwrap()
    }

    #[test]
    fn a_compressed_file_reads_as_its_content_and_a_plain_one_as_it_is() {
        let dir = std::env::temp_dir().join(format!("mapc-gz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = b"<routes>\n  <flow id=\"f\"/>\n</routes>\n";
        let (plain, gz) = (dir.join("r.rou.xml"), dir.join("r.rou.xml.gz"));
        std::fs::write(&plain, text).unwrap();
        std::fs::write(&gz, compressed(text)).unwrap();
        assert_eq!(read_input(&plain).unwrap(), text);
        assert_eq!(read_input(&gz).unwrap(), text);
        assert_eq!(read_head(&gz).unwrap(), (text.to_vec(), true));
        assert_eq!(read_head(&plain).unwrap(), (text.to_vec(), false));
        // cut short: an error that says the file was compressed
        let whole = compressed(text);
        std::fs::write(&gz, &whole[..whole.len() / 2]).unwrap();
        let e = read_input(&gz).unwrap_err().to_string();
        assert!(e.contains("gzip-compressed"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn the_name_without_gz_tells_the_format() {
        assert_eq!(
            inner_name(Path::new("a/x.net.xml.gz")),
            Path::new("a/x.net.xml")
        );
        assert_eq!(
            inner_name(Path::new("x.NET.XML.GZ")),
            Path::new("x.NET.XML")
        );
        assert_eq!(inner_name(Path::new("x.net.xml")), Path::new("x.net.xml"));
        assert!(is_gzip(&[0x1f, 0x8b, 8]) && !is_gzip(b"<net"));
    }
}
