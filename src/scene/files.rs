//! The one gate every file a scene reads passes through: textures, environment maps, models,
//! their MTL files, glTF buffers and images, 3DS textures, voxel grids. While a scene loads
//! (`collect`), each file opened through `read` or `check` is
//!
//! - recorded (resolved through links), so no command that writes may replace it
//!   (`Scene::inputs`, checked by `io::image::check_not_input`); and
//! - when the load is confined (the editor's server), refused unless it lies inside the scene's
//!   folder once every link is followed, with a message that names neither the file nor what it
//!   holds, so the editor's page learns nothing about files outside the folder.
//!
//! The scope lives in a thread-local: every loader reads on the thread that loads the scene (the
//! scene converter and the model importers are sequential; rayon works on decoded data only),
//! so no loader's signature has to carry it. Reads outside `collect` (tests, tools) are neither
//! recorded nor confined.

use std::cell::RefCell;
use std::path::{Path, PathBuf};

struct Scope {
    /// The canonical folder reads must stay inside; `None` allows any file.
    confine: Option<PathBuf>,
    /// Canonical folders readable besides `confine` (POV-Ray's standard include folder).
    also: Vec<PathBuf>,
    /// Every file read so far, canonical, in first-read order without repeats.
    read: Vec<PathBuf>,
}

thread_local! {
    static SCOPE: RefCell<Vec<Scope>> = const { RefCell::new(Vec::new()) };
}

/// Why a file was not read. `Display` is the reason only; the caller names the field or file.
#[derive(Debug)]
pub enum FileError {
    /// The file is outside the folder the load is confined to (or does not exist there).
    Outside { folder: PathBuf },
    /// The OS refused (not found, permissions): the error, as `std::fs` gives it.
    Io(std::io::Error),
    /// The file is larger than `limit` bytes (or endless, like /dev/zero).
    TooLarge { limit: u64 },
    /// Reading the file (`size` bytes) would take more than the memory available.
    NoMemory { size: u64, available: u64 },
}

impl std::fmt::Display for FileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FileError::Outside { folder } => write!(
                f,
                "the file is not inside the scene's folder ({}); the editor reads only files inside it",
                folder.display()
            ),
            FileError::Io(e) => write!(f, "{e}"),
            FileError::TooLarge { limit } => write!(
                f,
                "the file is larger than {} (the most photonix reads; see docs/limits.md)",
                crate::limits::fmt_bytes(*limit)
            ),
            FileError::NoMemory { size, available } => write!(
                f,
                "the file holds {} and only {} of memory is available to read it (docs/limits.md, Memory)",
                crate::limits::fmt_bytes(*size),
                crate::limits::fmt_bytes(*available)
            ),
        }
    }
}

impl std::error::Error for FileError {}

impl FileError {
    /// True when the file does not exist (and the load is not confined, or it would be inside).
    pub fn not_found(&self) -> bool {
        matches!(self, FileError::Io(e) if e.kind() == std::io::ErrorKind::NotFound)
    }
}

/// Runs `load` with a fresh scope and returns its result with every file it read (canonical,
/// first-read order). With `confine`, reads outside that folder fail; `confine` must be canonical.
/// Scopes nest: an inner load's files are added to the outer one's too.
pub fn collect<T>(confine: Option<&Path>, load: impl FnOnce() -> T) -> (T, Vec<PathBuf>) {
    collect_allowing(confine, &[], load)
}

/// `collect`, where a confined load may also read inside the folders `also` (canonical; those
/// that do not exist are dropped): POV-Ray's standard include folder beside the scene's own.
/// An inner scope keeps the outer scope's extra folders and adds none of its own to them.
pub fn collect_allowing<T>(confine: Option<&Path>, also: &[&Path], load: impl FnOnce() -> T) -> (T, Vec<PathBuf>) {
    // An inner scope keeps the outer confinement: it may narrow it, never lift it.
    let outer = SCOPE.with(|s| s.borrow().last().map(|scope| (scope.confine.clone(), scope.also.clone())));
    let (confine, also) = match (confine, outer) {
        (Some(inner), Some((Some(outer), outer_also))) if inner.starts_with(&outer) => {
            (Some(inner.to_path_buf()), outer_also)
        }
        (_, Some((Some(outer), outer_also))) => (Some(outer), outer_also),
        (inner, _) => {
            (inner.map(Path::to_path_buf), also.iter().filter_map(|a| std::fs::canonicalize(a).ok()).collect())
        }
    };
    SCOPE.with(|s| s.borrow_mut().push(Scope { confine, also, read: Vec::new() }));
    // Pop the scope even when `load` unwinds (the glTF reader's panics are caught above us).
    struct PopOnUnwind;
    impl Drop for PopOnUnwind {
        fn drop(&mut self) {
            pop();
        }
    }
    let guard = PopOnUnwind;
    let result = load();
    std::mem::forget(guard);
    (result, pop())
}

/// The current scope's folder and extra folders (`collect_allowing`), to carry a load onto
/// another thread: run it there under `collect_allowing` with these, then `record` what it read.
pub fn current_rules() -> (Option<PathBuf>, Vec<PathBuf>) {
    SCOPE.with(|s| s.borrow().last().map(|scope| (scope.confine.clone(), scope.also.clone())).unwrap_or_default())
}

/// Records files read on another thread in the current scope (canonical paths).
pub fn record(paths: &[PathBuf]) {
    for path in paths {
        note_read(path.clone());
    }
}

/// Pops the innermost scope, adds its files to the scope around it, and returns them.
fn pop() -> Vec<PathBuf> {
    let read = SCOPE.with(|s| s.borrow_mut().pop()).map(|scope| scope.read).unwrap_or_default();
    for path in &read {
        note_read(path.clone());
    }
    read
}

fn current_confinement() -> Option<PathBuf> {
    SCOPE.with(|s| s.borrow().last().and_then(|scope| scope.confine.clone()))
}

/// True when the current scope allows the canonical `path`: no confinement, or inside the
/// folder or one of the extra folders.
fn allowed(path: &Path) -> bool {
    SCOPE.with(|s| match s.borrow().last() {
        Some(Scope { confine: Some(folder), also, .. }) => {
            path.starts_with(folder) || also.iter().any(|a| path.starts_with(a))
        }
        _ => true,
    })
}

/// Records `path` (canonical) in the innermost scope, if any.
fn note_read(path: PathBuf) {
    SCOPE.with(|s| {
        if let Some(scope) = s.borrow_mut().last_mut() {
            if !scope.read.contains(&path) {
                scope.read.push(path);
            }
        }
    });
}

/// Checks that `path` may be read in the current scope and records it; returns the path to open
/// (canonical when it exists). Use it where a library opens the file itself (the glTF reader).
pub fn check(path: &Path) -> Result<PathBuf, FileError> {
    let resolved = probe(path)?;
    note_read(resolved.clone());
    Ok(resolved)
}

/// `check` without recording the file: whether `path` may be read here (a search along include
/// folders, `file_exists`), with the same refusal, naming nothing, for a path outside.
pub fn probe(path: &Path) -> Result<PathBuf, FileError> {
    let resolved = std::fs::canonicalize(path);
    if let Some(folder) = current_confinement() {
        // A missing file is reported as outside too: whether a path exists outside the folder
        // is itself something the page must not learn.
        match &resolved {
            Ok(r) if allowed(r) => {}
            Ok(_) => return Err(FileError::Outside { folder }),
            Err(e) => {
                // Missing inside the folder: say so (the page can fix its own typo). Decide by
                // the nearest existing ancestor, resolved, so `inside/../../x` is outside.
                let ancestor = path.ancestors().skip(1).find_map(|a| {
                    let a = if a.as_os_str().is_empty() { Path::new(".") } else { a };
                    std::fs::canonicalize(a).ok()
                });
                let below_ancestor = path.components().all(|c| !matches!(c, std::path::Component::ParentDir));
                match ancestor {
                    Some(a) if a.starts_with(&folder) && below_ancestor => {
                        return Err(FileError::Io(std::io::Error::new(e.kind(), e.to_string())))
                    }
                    _ => return Err(FileError::Outside { folder }),
                }
            }
        }
    }
    resolved.map_err(FileError::Io)
}

/// `check`, and `path` must be a regular file (not a device, a pipe or a folder) of at most
/// `limit` bytes: for a library that opens the file itself (the glTF reader's buffers and
/// images), which would read an endless or huge file to its end.
pub fn check_file(path: &Path, limit: u64) -> Result<PathBuf, FileError> {
    let resolved = check(path)?;
    let size = crate::limits::regular_file_size(&resolved).map_err(FileError::Io)?;
    if size > limit {
        return Err(FileError::TooLarge { limit });
    }
    if let Some(available) = crate::render::memory::available_host_memory().filter(|a| size > *a) {
        return Err(FileError::NoMemory { size, available });
    }
    Ok(resolved)
}

/// Reads at most `limit` bytes of `path` after `check`; only a regular file is read, and only
/// when its size fits the memory available (the memory budget, docs/limits.md).
pub fn read(path: &Path, limit: u64) -> Result<Vec<u8>, FileError> {
    let resolved = check(path)?;
    if let Ok(size) = crate::limits::regular_file_size(&resolved) {
        if let Some(available) = crate::render::memory::available_host_memory() {
            if size <= limit && size > available {
                return Err(FileError::NoMemory { size, available });
            }
        }
    }
    crate::limits::read_limited(&resolved, limit).map_err(|e| match e {
        Some(e) => FileError::Io(e),
        None => FileError::TooLarge { limit },
    })
}

/// Lists `dir` (for a case-insensitive file lookup) after the same confinement check.
pub fn read_dir(dir: &Path) -> Option<std::fs::ReadDir> {
    let dir = std::fs::canonicalize(dir).ok()?;
    if !allowed(&dir) {
        return None;
    }
    std::fs::read_dir(dir).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_are_recorded_and_confined() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("scene");
        std::fs::create_dir(&folder).unwrap();
        std::fs::write(folder.join("a.txt"), b"a").unwrap();
        std::fs::write(dir.path().join("secret.txt"), b"s").unwrap();
        std::os::unix::fs::symlink(dir.path().join("secret.txt"), folder.join("link.txt")).unwrap();
        let folder = folder.canonicalize().unwrap();

        let (bytes, seen) = collect(None, || read(&folder.join("a.txt"), 10).unwrap());
        assert_eq!(bytes, b"a");
        assert_eq!(seen, vec![folder.join("a.txt")]);

        let ((), seen) = collect(Some(&folder), || {
            assert!(read(&folder.join("a.txt"), 10).is_ok());
            for outside in ["../secret.txt", "link.txt", "../missing.txt", "/etc/passwd", "sub/../../secret.txt"] {
                let e = read(&folder.join(outside), 10).unwrap_err();
                assert!(matches!(e, FileError::Outside { .. }), "{outside}: {e}");
                assert!(!e.to_string().contains("secret"), "{e}");
            }
            let e = read(&folder.join("missing.txt"), 10).unwrap_err();
            assert!(e.not_found(), "{e}");
            // An inner scope cannot lift the confinement.
            let (r, _) = collect(None, || read(&folder.join("../secret.txt"), 10));
            assert!(r.is_err());
        });
        assert_eq!(seen, vec![folder.join("a.txt")]);
        // Outside any scope nothing is confined.
        assert!(super::read(&dir.path().join("secret.txt"), 10).is_ok());
        assert!(matches!(super::read(&folder.join("a.txt"), 0), Err(FileError::TooLarge { .. })));
    }
}
