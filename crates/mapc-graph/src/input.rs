//! Reading an input file (a map, a graph, a scenario, a policy) with a size cap. A path may name anything: a
//! device that never ends (`/dev/zero`), a FIFO, a file far larger than any map; without a cap, reading it would
//! run until memory runs out. Every reader of mapc's inputs goes through [`open`] or [`read`]: a regular file
//! larger than the cap is refused before a byte is read, and anything else is read only up to the cap.
//!
//! The cap is [`DEFAULT_MAX_INPUT_MB`] megabytes unless the environment variable [`MAX_INPUT_ENV`]
//! (`MAPC_MAX_INPUT_MB`) gives another whole number of megabytes.

use std::io::Read;
use std::path::Path;

/// The environment variable that sets the cap, in megabytes (MiB).
pub const MAX_INPUT_ENV: &str = "MAPC_MAX_INPUT_MB";
/// The cap without [`MAX_INPUT_ENV`]: far above any map mapc was made for, far below what exhausts a machine.
pub const DEFAULT_MAX_INPUT_MB: u64 = 1024;

/// The cap in bytes; an unreadable [`MAX_INPUT_ENV`] is an error that says what it should be.
pub fn max_input_bytes() -> std::io::Result<u64> {
    let megabytes = match std::env::var(MAX_INPUT_ENV) {
        Err(_) => DEFAULT_MAX_INPUT_MB,
        Ok(text) => text
            .trim()
            .parse::<u64>()
            .ok()
            .filter(|&mb| mb > 0)
            .ok_or_else(|| {
                std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!("{MAX_INPUT_ENV}={text:?} is not a positive whole number of megabytes"),
                )
            })?,
    };
    Ok(megabytes.saturating_mul(1 << 20))
}

fn too_large(cap: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::FileTooLarge,
        format!(
            "larger than {} MB, the most mapc reads of an input (set {MAX_INPUT_ENV} to read more)",
            cap >> 20
        ),
    )
}

/// A reader that fails once more than its cap has come through, rather than reading on.
pub struct Capped<R> {
    inner: R,
    cap: u64,
    read: u64,
}

impl<R: Read> Read for Capped<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        // one byte past the cap is enough to know the input is over it
        let room = (self.cap + 1 - self.read).min(buf.len() as u64) as usize;
        let n = self.inner.read(&mut buf[..room])?;
        self.read += n as u64;
        if self.read > self.cap {
            return Err(too_large(self.cap));
        }
        Ok(n)
    }
}

/// `inner` read under the cap: a stream whose size no file bounds (a decompressed input).
pub fn capped<R: Read>(inner: R) -> std::io::Result<Capped<R>> {
    Ok(Capped {
        inner,
        cap: max_input_bytes()?,
        read: 0,
    })
}

/// `path` opened for reading under the cap; a regular file already over it is refused here.
pub fn open(path: &Path) -> std::io::Result<Capped<std::fs::File>> {
    let cap = max_input_bytes()?;
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if meta.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "is a directory, not a file",
        ));
    }
    if meta.is_file() && meta.len() > cap {
        return Err(too_large(cap));
    }
    Ok(Capped {
        inner: file,
        cap,
        read: 0,
    })
}

/// The whole of `path`, under the cap.
pub fn read(path: &Path) -> std::io::Result<Vec<u8>> {
    let mut reader = open(path)?;
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// The whole of `path` as UTF-8 text, under the cap.
pub fn read_to_string(path: &Path) -> std::io::Result<String> {
    String::from_utf8(read(path)?)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_endless_device_is_read_only_up_to_the_cap() {
        let mut capped = Capped {
            inner: std::io::repeat(0),
            cap: 1 << 20,
            read: 0,
        };
        let err = capped.read_to_end(&mut Vec::new()).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::FileTooLarge);
        assert!(err.to_string().contains("larger than 1 MB"), "{err}");
        assert!(err.to_string().contains(MAX_INPUT_ENV), "{err}");
        assert!(capped.read <= (1 << 20) + 1);
    }

    #[test]
    fn input_at_the_cap_is_read_whole() {
        let mut capped = Capped {
            inner: &[7u8; 1000][..],
            cap: 1000,
            read: 0,
        };
        let mut out = Vec::new();
        capped.read_to_end(&mut out).unwrap();
        assert_eq!(out.len(), 1000);
    }
}
