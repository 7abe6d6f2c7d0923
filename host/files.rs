//! Files the program reads and writes: errors that say where a file is wrong, and writes
//! that happen whole or not at all.

use std::fmt;
use std::io::Write;
use std::path::Path;

/// What is wrong with a file the program reads (a scene, a replay), and where.
///
/// Displays as `{file}:{line}: {field}: {problem}`, without `:{line}` when the line is
/// unknown and without `{field}: ` when no field is concerned.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub struct FileError {
    /// The path as given, or what the text is (``built-in scene `paper` ``).
    pub file: String,
    /// 1-based line, when the error points into the text.
    pub line: Option<usize>,
    /// The key concerned, spelled as in the file (`kinds[2].mass`, `inputs[17].aim`), or
    /// empty.
    pub field: String,
    /// What is wrong and, for ranges, what is allowed.
    pub problem: String,
}

impl FileError {
    /// An error in `file`.
    pub fn new(
        file: &str,
        line: Option<usize>,
        field: impl fmt::Display,
        problem: impl fmt::Display,
    ) -> Self {
        FileError {
            file: file.to_owned(),
            line,
            field: field.to_string(),
            problem: problem.to_string(),
        }
    }
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        f.write_str(": ")?;
        if !self.field.is_empty() {
            write!(f, "{}: ", self.field)?;
        }
        f.write_str(&self.problem)
    }
}

/// The 1-based line of byte `at` of `text` (bytes past the end count as the end).
pub fn line_of(text: &[u8], at: usize) -> usize {
    1 + text[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// Writes `bytes` to `path` atomically: into a temporary file in the same directory, flushed
/// and synced to disk, readable by all like any data file (0644 on Unix; a temporary file
/// starts private), then renamed over `path`. On any error `path` is left as it was and the
/// temporary file is removed.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    // `Path::new("x").parent()` is the empty path, which `new_in` does not take.
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let mut file = tempfile::NamedTempFile::new_in(dir)?;
    file.write_all(bytes)?;
    file.flush()?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        file.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))?;
    }
    file.as_file().sync_all()?;
    file.persist(path).map_err(|e| e.error)?;
    Ok(())
}
