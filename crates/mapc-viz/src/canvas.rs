//! Choosing the drawing backend from the output's name and writing the file atomically.

use crate::VizError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// A picture that can be drawn on any plotters backend.
pub(crate) trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// Turn any displayable drawing error into the message `Figure::draw` returns.
pub(crate) trait DrawErr<T> {
    fn d(self) -> Result<T, String>;
}
impl<T, E: std::fmt::Display> DrawErr<T> for Result<T, E> {
    fn d(self) -> Result<T, String> {
        self.map_err(|e| e.to_string())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PictureKind {
    Png,
    Svg,
}

pub(crate) fn picture_kind(path: &Path) -> Result<PictureKind, VizError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "png" => Ok(PictureKind::Png),
        "svg" => Ok(PictureKind::Svg),
        _ => Err(VizError::PictureType {
            path: path.to_path_buf(),
        }),
    }
}

/// Draw `figure` into `out` (`.png` or `.svg`), `size` pixels, replacing any old file only once the new one is
/// complete.
pub(crate) fn draw_to_file(
    out: &Path,
    size: (u32, u32),
    figure: &impl Figure,
) -> Result<(), VizError> {
    let kind = picture_kind(out)?;
    let draw_err = |message: String| VizError::Draw {
        path: out.to_path_buf(),
        message,
    };
    let io_err = |source: std::io::Error| VizError::Io {
        path: out.to_path_buf(),
        source,
    };
    match kind {
        PictureKind::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
                figure.draw(&root).map_err(draw_err)?;
                root.present().d().map_err(draw_err)?;
            }
            // the backend escapes `<` and `&` in labels but passes control characters a map's names may hold
            let svg = mapc_graph::markup::xml_safe(&svg);
            mapc_graph::write_atomically(out, svg.as_bytes()).map_err(io_err)
        }
        PictureKind::Png => {
            let tmp = temp_beside(out)?;
            let result = (|| {
                {
                    let root = BitMapBackend::new(&tmp, size).into_drawing_area();
                    figure.draw(&root).map_err(draw_err)?;
                    root.present().d().map_err(draw_err)?;
                }
                std::fs::rename(&tmp, out).map_err(io_err)
            })();
            if result.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
            result
        }
    }
}

/// A hidden temporary name in `out`'s directory that keeps its extension (the bitmap encoder picks the format from
/// it), so that the final rename stays on one file system.
fn temp_beside(out: &Path) -> Result<PathBuf, VizError> {
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|source| VizError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(dir.join(format!(".{name}.{}.tmp.{ext}", std::process::id())))
}
