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
pub struct Files {
    /// (name, bytes), in order.
    pub entries: Vec<(String, Vec<u8>)>,
    /// Written into a folder that other runs write too (the shards of an array): see
    /// [`Files::shared`].
    shared: bool,
}

impl Files {
    /// No files yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// These files for a folder that other runs write into too — the tasks of an array, each
    /// with its own shard's files: [`Files::write`] then writes each file atomically and
    /// touches nothing else there (no record of the run, no file of another run removed).
    pub fn shared(mut self) -> Self {
        self.shared = true;
        self
    }

    /// See [`Files::shared`].
    fn write_shared(&self, dir: &Path) -> Result<Written, OutputError> {
        fs::create_dir_all(dir).map_err(|source| OutputError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let mut files = Vec::new();
        for (name, bytes) in &self.entries {
            let path = dir.join(name);
            write_atomic(&path, bytes)?;
            files.push(path);
        }
        Ok(Written {
            files,
            left: Vec::new(),
        })
    }

    /// A text file.
    pub fn text(&mut self, name: &str, text: impl Into<String>) {
        self.entries
            .push((name.to_string(), text.into().into_bytes()));
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
        self.entries.push((format!("{stem}.png"), figure.png()?));
        Ok(())
    }

    /// The names, in order.
    pub fn names(&self) -> Vec<&str> {
        self.entries.iter().map(|(n, _)| n.as_str()).collect()
    }

    /// Writes every file into `dir` (created if missing, subfolders too), each atomically;
    /// all or nothing: after a failure nothing of this call is left. Files that an earlier
    /// write into `dir` made and this one does not (a figure of a state that no longer moves)
    /// are removed, so a reused folder never mixes two runs; `dir`'s other files are left
    /// alone. What was written is recorded in `dir/.twv-files` with each file's SHA-256, and a
    /// stale file is removed only while it is still a regular file inside `dir` (no symbolic
    /// link on the way) with the bytes twv wrote: a file the user changed, added to the list or
    /// linked elsewhere is left where it is, with a note in [`Written::left`].
    pub fn write(&self, dir: &Path) -> Result<Written, OutputError> {
        if self.shared {
            return self.write_shared(dir);
        }
        let manifest = dir.join(MANIFEST);
        let previous = match fs::symlink_metadata(&manifest) {
            Ok(meta) if meta.is_file() => fs::read_to_string(&manifest).unwrap_or_default(),
            _ => String::new(),
        };
        let mut out = OutputDir::create(dir)?;
        for (name, bytes) in &self.entries {
            out.write(name, bytes)?;
        }
        let listed: String = self
            .entries
            .iter()
            .map(|(name, bytes)| format!("{}  {name}\n", sha256_hex(bytes)))
            .collect();
        write_atomic(&manifest, listed.as_bytes())?;
        let files = out.commit();
        let current: std::collections::HashSet<&str> = self.names().into_iter().collect();
        let mut left = Vec::new();
        for line in previous.lines().filter(|l| !l.trim().is_empty()) {
            let (hash, name) = line.split_once("  ").unwrap_or(("", line));
            if current.contains(name) {
                continue;
            }
            if let Err(why) = remove_own(dir, name, hash) {
                left.push(format!("left {} in place: {why}", dir.join(name).display()));
            }
        }
        Ok(Written { files, left })
    }
}

/// What [`Files::write`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Written {
    /// The files written, in order.
    pub files: Vec<PathBuf>,
    /// Files of an earlier run that were not removed, each with the reason (one line each).
    pub left: Vec<String>,
}

/// SHA-256 of `bytes` in hex (the manifest's record of what twv wrote).
fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Removes `dir/name` if it is what twv wrote there (`hash`): a relative name of plain
/// components, no symbolic link on the way or at the end, a regular file with those bytes.
fn remove_own(dir: &Path, name: &str, hash: &str) -> Result<(), &'static str> {
    use std::path::Component;
    let relative = Path::new(name);
    if name.is_empty()
        || !relative
            .components()
            .all(|c| matches!(c, Component::Normal(_)))
    {
        return Err("its name in .twv-files is not a plain name inside the folder");
    }
    if hash.len() != 64 {
        return Err("its entry in .twv-files has no content hash (an older twv, or not twv's)");
    }
    let mut path = dir.to_path_buf();
    let components: Vec<_> = relative.components().collect();
    for (i, part) in components.iter().enumerate() {
        path.push(part);
        let Ok(meta) = fs::symlink_metadata(&path) else {
            return Err("it is gone");
        };
        if meta.file_type().is_symlink() {
            return Err("a symbolic link is on its path (twv never follows one to remove a file)");
        }
        let last = i + 1 == components.len();
        if last && !meta.is_file() {
            return Err("it is not a regular file");
        }
    }
    let bytes = fs::read(&path).map_err(|_| "it cannot be read")?;
    if sha256_hex(&bytes) != hash {
        return Err("it changed since twv wrote it");
    }
    fs::remove_file(&path).map_err(|_| "it cannot be removed")
}

/// The list of files the last [`Files::write`] put into a folder, with their SHA-256.
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
    ///
    /// A subfolder on the way that is a symbolic link is refused: twv writes only into real
    /// folders inside the output folder.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        let path = self.dir.join(name);
        let mut inside = self.dir.clone();
        for part in Path::new(name).components() {
            inside.push(part);
            if fs::symlink_metadata(&inside).is_ok_and(|m| m.file_type().is_symlink()) {
                return Err(OutputError::Io {
                    path: inside.clone(),
                    source: std::io::Error::other(
                        "it is a symbolic link; twv writes only into real folders inside the \
                         output folder",
                    ),
                });
            }
        }
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

/// Atomic writes under way in this process: a front end that exits at once on a second Ctrl-C
/// waits for this to be 0 first ([`writes_in_flight`]), so that an interrupt during a
/// checkpoint's write cannot leave a temporary file and no checkpoint.
static WRITES_IN_FLIGHT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// How many [`write_atomic`] calls are between their first byte and their rename.
pub fn writes_in_flight() -> usize {
    WRITES_IN_FLIGHT.load(std::sync::atomic::Ordering::SeqCst)
}

/// Counts one write in flight while it lives: a file being written, or a run that ends in a
/// write once cancelled (a sweep's shard, whose checkpoint follows the chunk it finishes).
pub struct InFlight;

impl InFlight {
    /// Counts from now until dropped.
    #[allow(clippy::new_without_default)]
    pub fn new() -> Self {
        WRITES_IN_FLIGHT.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        InFlight
    }
}

impl Drop for InFlight {
    fn drop(&mut self) {
        WRITES_IN_FLIGHT.fetch_sub(1, std::sync::atomic::Ordering::SeqCst);
    }
}

/// Write a file via a temporary sibling and a rename, so readers never see half a file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let _in_flight = InFlight::new();
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
