//! A directory of files written so that nothing is half-written: everything goes into a temporary directory beside
//! the target, which then replaces the target by renames; on any error the temporary is removed and the target
//! is left as it was.

use crate::ExportError;
use std::path::{Path, PathBuf};

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ExportError + '_ {
    move |error| ExportError::Io {
        path: path.to_path_buf(),
        error,
    }
}

/// Write `files` (name, text) as the whole content of `dir`.
pub fn write_dir(dir: &Path, files: &[(String, String)]) -> Result<(), ExportError> {
    if dir.exists() && !dir.is_dir() {
        return Err(ExportError::NotADirectory {
            path: dir.to_path_buf(),
        });
    }
    let parent = dir
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| ExportError::NotADirectory {
            path: dir.to_path_buf(),
        })?;
    std::fs::create_dir_all(parent).map_err(io(parent))?;
    let tmp: PathBuf = parent.join(format!(".{name}.{}.tmp", std::process::id()));
    let old: PathBuf = parent.join(format!(".{name}.{}.old", std::process::id()));
    let result = (|| {
        let _ = std::fs::remove_dir_all(&tmp);
        std::fs::create_dir(&tmp).map_err(io(&tmp))?;
        for (file, text) in files {
            let path = tmp.join(file);
            mapc_graph::write_atomically(&path, text.as_bytes()).map_err(io(&path))?;
        }
        let had_old = dir.exists();
        if had_old {
            std::fs::rename(dir, &old).map_err(io(dir))?;
        }
        if let Err(e) = std::fs::rename(&tmp, dir) {
            if had_old {
                let _ = std::fs::rename(&old, dir);
            }
            return Err(io(dir)(e));
        }
        if had_old {
            let _ = std::fs::remove_dir_all(&old);
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    result
}
