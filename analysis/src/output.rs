//! Result files written atomically: each file goes to a temporary name in its folder and is
//! renamed into place, and a run that fails removes what it had already written, so a user never
//! finds partial or corrupt output.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Why an output could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The output folder cannot be created or written.
    #[error("cannot write to {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// The files of a result, in memory: (name relative to the output folder, bytes). Jobs build
/// them without touching the disk; [`Files::write`] is the one shared step that does.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Files(pub Vec<(String, Vec<u8>)>);

impl Files {
    /// No files yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// A text file.
    pub fn text(&mut self, name: &str, text: impl Into<String>) {
        self.0.push((name.to_string(), text.into().into_bytes()));
    }

    /// A pretty-printed JSON file.
    pub fn json<T: serde::Serialize>(&mut self, name: &str, value: &T) {
        let text = serde_json::to_string_pretty(value).unwrap_or_else(|e| format!("{e}"));
        self.text(name, text + "\n");
    }

    /// A figure as `name` (ending in `.svg`) and its PNG beside it.
    pub fn figure(
        &mut self,
        name: &str,
        figure: &crate::plot::Figure,
    ) -> Result<(), crate::plot::PlotError> {
        self.text(name, figure.svg()?);
        let stem = name.strip_suffix(".svg").unwrap_or(name);
        self.0.push((format!("{stem}.png"), figure.png()?));
        Ok(())
    }

    /// The names, in order.
    pub fn names(&self) -> Vec<&str> {
        self.0.iter().map(|(n, _)| n.as_str()).collect()
    }

    /// Writes every file into `dir` (created if missing, subfolders too), each atomically;
    /// all or nothing: after a failure nothing of this call is left. Files that an earlier
    /// write into `dir` made and this one does not (a figure of a state that no longer moves)
    /// are removed, so a reused folder never mixes two runs; `dir`'s other files are left
    /// alone (the names written are kept in `dir/.twv-files`).
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, OutputError> {
        let manifest = dir.join(MANIFEST);
        let previous = fs::read_to_string(&manifest).unwrap_or_default();
        let mut out = OutputDir::create(dir)?;
        for (name, bytes) in &self.0 {
            out.write(name, bytes)?;
        }
        let names = self.names().join("\n") + "\n";
        write_atomic(&manifest, names.as_bytes())?;
        let written = out.commit();
        let current: std::collections::HashSet<&str> = self.names().into_iter().collect();
        for stale in previous
            .lines()
            .filter(|n| !n.is_empty() && !current.contains(n))
        {
            // Only plain relative names this writer made; never climb out of `dir`.
            if !stale.contains("..") && !Path::new(stale).is_absolute() {
                let _ = fs::remove_file(dir.join(stale));
            }
        }
        Ok(written)
    }
}

/// The list of files the last [`Files::write`] put into a folder.
const MANIFEST: &str = ".twv-files";

/// A folder receiving the files of one run.
///
/// Files are only kept when [`OutputDir::commit`] is called; dropping an uncommitted
/// `OutputDir` (an error part-way) deletes the files it wrote and the folder if it created it.
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    created: bool,
    written: Vec<PathBuf>,
    /// Subfolders this run created, innermost last.
    subdirs: Vec<PathBuf>,
    committed: bool,
}

impl OutputDir {
    /// Create (if needed) and check the folder by writing a probe file.
    pub fn create(dir: &Path) -> Result<Self, OutputError> {
        let io = |source| OutputError::Io {
            path: dir.to_path_buf(),
            source,
        };
        let created = !dir.exists();
        fs::create_dir_all(dir).map_err(io)?;
        let probe = dir.join(".twv-write-probe");
        fs::write(&probe, b"").map_err(io)?;
        fs::remove_file(&probe).map_err(io)?;
        Ok(Self {
            dir: dir.to_path_buf(),
            created,
            written: Vec::new(),
            subdirs: Vec::new(),
            committed: false,
        })
    }

    /// The folder's path.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Write `name` (which may name a subfolder, `figures/a.svg`) atomically (temporary file
    /// + rename) and remember it.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        let path = self.dir.join(name);
        if let Some(parent) = path.parent() {
            if !parent.exists() {
                fs::create_dir_all(parent).map_err(|source| OutputError::Io {
                    path: parent.to_path_buf(),
                    source,
                })?;
                self.subdirs.push(parent.to_path_buf());
            }
        }
        write_atomic(&path, bytes)?;
        self.written.push(path.clone());
        Ok(path)
    }

    /// Keep the written files.
    pub fn commit(mut self) -> Vec<PathBuf> {
        self.committed = true;
        std::mem::take(&mut self.written)
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        for path in &self.written {
            let _ = fs::remove_file(path);
        }
        for dir in self.subdirs.iter().rev() {
            let _ = fs::remove_dir(dir);
        }
        if self.created {
            let _ = fs::remove_dir(&self.dir);
        }
    }
}

/// Write a file via a temporary sibling and a rename, so readers never see half a file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let io = |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    };
    let parent = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = parent.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut file = fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// A table as CSV: the header, then one row per line, every number in full precision (`{:e}`,
/// which round-trips).
pub fn csv_table(columns: &[String], rows: &[Vec<f64>]) -> String {
    let mut s = columns.join(",");
    s.push('\n');
    for r in rows {
        let cells: Vec<String> = r.iter().map(|v| format!("{v:e}")).collect();
        s += &cells.join(",");
        s.push('\n');
    }
    s
}
