//! Files the program reads and writes: errors that say where a file is wrong, in the user's
//! words; reads that take only regular files of a bounded size; and writes that happen whole
//! or not at all, and only over what the program may replace.

use std::fmt;
use std::fs::{File, FileType};
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};

pub mod positioned;

/// Most bytes of a scene file (the built-in ones take a few thousand).
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// Most characters of a value an error quotes.
const EXCERPT_CHARS: usize = 40;
/// Most characters of an error's field and problem: a backstop, in case some message quotes
/// more of a huge input than it should.
const MAX_FIELD_CHARS: usize = 120;
const MAX_PROBLEM_CHARS: usize = 600;
/// Most characters of a file's name an error shows from its start, and from its end (where
/// the file's own name is): a long path is shown as both, `…` between.
const NAME_HEAD: usize = 30;
const NAME_TAIL: usize = 50;

/// What is wrong with a file the program reads (a scene, a replay) or writes, and where.
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
    /// An error in `file` (a long name shortened, field and problem cut short if some
    /// input made them huge).
    pub fn new(
        file: &str,
        line: Option<usize>,
        field: impl fmt::Display,
        problem: impl fmt::Display,
    ) -> Self {
        FileError {
            file: short_name(file),
            line,
            field: cap(&field.to_string(), MAX_FIELD_CHARS),
            problem: cap(&problem.to_string(), MAX_PROBLEM_CHARS),
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

/// `text` as an error may quote it: its first line, at most a few dozen characters (`…`
/// marks a cut), control characters escaped so that a hostile file cannot drive the
/// terminal.
pub fn excerpt(text: &str) -> String {
    let mut lines = text.lines();
    let (first, cut) = shorten(lines.next().unwrap_or_default(), EXCERPT_CHARS);
    let mut out = escaped(&first);
    if cut || lines.next().is_some() {
        out.push('…');
    }
    out
}

/// `text` with its control characters escaped as JSON and TOML write them (`\n`,
/// `\u001b`).
fn escaped(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => out.push_str(&format!("\\u{:04x}", u32::from(c))),
            c => out.push(c),
        }
    }
    out
}

/// What a JSON parse error means, in words (without serde_json's position, which the
/// error gives as its line).
pub fn json_problem(e: &serde_json::Error) -> String {
    let message = e.to_string();
    let position = format!(" at line {} column {}", e.line(), e.column());
    let message = message.strip_suffix(&position).unwrap_or(&message);
    let said = match message {
        "EOF while parsing a list" => "the text ends inside a list (a `]` is missing)",
        "EOF while parsing an object" => "the text ends inside an object (a `}` is missing)",
        "EOF while parsing a string" => "the text ends inside a string (a `\"` is missing)",
        "EOF while parsing a value" => "the text ends where a value should be",
        "expected ident" | "expected value" => {
            "not a JSON value (a number, a \"string\", true, false, null, a list or an object)"
        }
        "expected `:`" => "a `:` should follow the key",
        "expected `,` or `]`" => "a `,` or `]` should follow the list's item",
        "expected `,` or `}`" => "a `,` or `}` should follow the object's value",
        "key must be a string" => "a key must be a \"string\" in double quotes",
        "invalid escape" => "a backslash that starts no escape of JSON (\\n, \\\", \\uXXXX, …)",
        "invalid number" => "not a number",
        "number out of range" => "a number too large to read",
        "invalid unicode code point" | "lone leading surrogate in hex escape" => {
            "a \\u escape that is not a character"
        }
        "unexpected end of hex escape" => "a \\u escape needs 4 hexadecimal digits",
        "trailing comma" => "a `,` before the closing bracket",
        "trailing characters" => "more text after the end of the JSON value",
        "recursion limit exceeded" => "lists or objects nested too deeply",
        m if m.starts_with("control character") => {
            "a control character inside a string (write it as an escape, such as \\n)"
        }
        // The readers' own errors (already in words) and anything new.
        m => return m.to_owned(),
    };
    said.to_owned()
}

/// A file's name as an error shows it: control characters escaped, and a long one cut to
/// its start and its end.
pub fn short_name(name: &str) -> String {
    let chars = name.chars().count();
    if chars <= NAME_HEAD + NAME_TAIL + 1 {
        return escaped(name);
    }
    let head: String = name.chars().take(NAME_HEAD).collect();
    let tail: String = name.chars().skip(chars - NAME_TAIL).collect();
    format!("{}…{}", escaped(&head), escaped(&tail))
}

/// The first `max` characters of `text`, and whether there were more.
fn shorten(text: &str, max: usize) -> (String, bool) {
    match text.char_indices().nth(max) {
        Some((at, _)) => (text[..at].to_owned(), true),
        None => (text.to_owned(), false),
    }
}

/// [`shorten`], with `…` where it cut.
fn cap(text: &str, max: usize) -> String {
    match shorten(text, max) {
        (out, true) => out + "…",
        (out, false) => out,
    }
}

/// `n` with its thousands separated by commas: `16,777,216`.
pub fn thousands(n: impl Into<i128>) -> String {
    let n: i128 = n.into();
    let digits = n.unsigned_abs().to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3 + 1);
    if n < 0 {
        out.push('-');
    }
    for (i, d) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(d);
    }
    out
}

/// `x` as a person writes it, in the fewest digits that read back as `x`: `0.5`, `60`,
/// `1000000`; `1e30`, `1.1754944e-38` beyond those; `inf` and `NaN`.
pub fn number(x: f32) -> String {
    let plain = x == 0.0 || !x.is_finite() || (1e-4..1e16).contains(&x.abs());
    if plain {
        format!("{x}")
    } else {
        format!("{x:?}")
    }
}

/// A measured figure in three significant digits: plainly from 0.001 to a million
/// (`11.8`, `0.0417`, `137`), in scientific notation beyond (`3.40e38`, `1.67e-31`); `0`,
/// `inf` and `NaN` as such.
pub fn figure(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    if !(1e-3..1e6).contains(&x.abs()) {
        return format!("{x:.2e}");
    }
    // Decimals for three significant digits, none past the units.
    let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

/// What a file system entry is, in words.
fn kind_of(file_type: FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if file_type.is_fifo() {
            return "a named pipe";
        }
        if file_type.is_char_device() || file_type.is_block_device() {
            return "a device";
        }
        if file_type.is_socket() {
            return "a socket";
        }
    }
    if file_type.is_dir() {
        "a folder"
    } else if file_type.is_symlink() {
        "a symbolic link"
    } else if file_type.is_file() {
        "a regular file"
    } else {
        "not a regular file"
    }
}

/// An I/O error in words, without the system's error number.
pub fn io_words(e: &std::io::Error) -> String {
    match e.kind() {
        ErrorKind::NotFound => "no such file".to_owned(),
        ErrorKind::PermissionDenied => "permission denied".to_owned(),
        _ => {
            let text = e.to_string();
            let text = text.split(" (os error").next().unwrap_or_default();
            let mut chars = text.chars();
            chars.next().map_or_else(String::new, |first| {
                first.to_lowercase().chain(chars).collect()
            })
        }
    }
}

/// `path` as a message shows it: see [`short_name`].
pub fn shown(path: &Path) -> String {
    short_name(&origin(path))
}

/// How errors name `path`: as given, and `""` for the empty path.
fn origin(path: &Path) -> String {
    match path.as_os_str().is_empty() {
        true => "\"\"".to_owned(),
        false => path.display().to_string(),
    }
}

/// The text of the regular file at `path`, at most `limit` bytes of UTF-8. Anything else is
/// refused before a byte is read: a folder, a named pipe (which would wait for a writer), a
/// device (which may never end), a larger file. Invalid UTF-8 is reported with its line and
/// column.
pub fn read_text(path: &Path, limit: u64) -> Result<String, FileError> {
    let name = origin(path);
    let fail = |problem: String| FileError::new(&name, None, "", problem);
    let cannot = |e: std::io::Error| fail(format!("cannot read: {}", io_words(&e)));
    let check = |meta: &std::fs::Metadata| {
        if !meta.is_file() {
            let what = kind_of(meta.file_type());
            return Err(fail(format!(
                "cannot read: it is {what} (allowed a regular file)"
            )));
        }
        if meta.len() > limit {
            return Err(fail(too_large(meta.len(), limit)));
        }
        Ok(())
    };
    // The path first, so that a named pipe is never opened (opening one waits for a writer).
    check(&std::fs::metadata(path).map_err(cannot)?)?;
    let file = File::open(path).map_err(cannot)?;
    // Then what was opened, in case the path changed in between.
    let meta = file.metadata().map_err(cannot)?;
    check(&meta)?;
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() as u64 > limit {
        return Err(fail(too_large(bytes.len() as u64, limit)));
    }
    utf8(bytes, &name)
}

/// The problem of a file of `bytes` bytes where at most `limit` are allowed.
fn too_large(bytes: u64, limit: u64) -> String {
    format!(
        "cannot read: it is {} bytes (allowed at most {})",
        thousands(bytes),
        thousands(limit)
    )
}

/// `bytes` as text, or an error at the line and column of the first byte that is not UTF-8.
fn utf8(bytes: Vec<u8>, origin: &str) -> Result<String, FileError> {
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line_start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        // Every byte before the bad one is valid: the column counts characters.
        let column = 1 + String::from_utf8_lossy(&valid[line_start..])
            .chars()
            .count();
        let byte = e.as_bytes()[valid.len()];
        let problem = format!(
            "not UTF-8 text: the byte 0x{byte:02x} at column {column} is not part of a character"
        );
        FileError::new(origin, Some(line_of(valid, valid.len())), "", problem)
    })
}

/// Checks that a file may be written at `path`: there is nothing there yet, or a regular
/// file that it replaces, in a folder that exists. A folder, a device, a named pipe or a
/// socket is never replaced; a symbolic link neither, and the error says how to write
/// through it or over it.
pub fn check_output(path: &Path) -> Result<(), FileError> {
    let name = origin(path);
    let fail =
        |problem: String| FileError::new(&name, None, "", format!("cannot write: {problem}"));
    if path.file_name().is_none() {
        return Err(fail("not a file name".to_owned()));
    }
    match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.is_file() => {}
        Ok(meta) if meta.file_type().is_symlink() => {
            // A relative target is relative to the link's folder.
            let target = match (std::fs::read_link(path), path.parent()) {
                (Ok(target), Some(dir)) => shown(&dir.join(target)),
                (Ok(target), None) => shown(&target),
                (Err(_), _) => "its target".to_owned(),
            };
            return Err(fail(format!(
                "it is a symbolic link, left as it is: to write to the file it points to, \
                 give {target}; to write a file in its place, remove the link first"
            )));
        }
        Ok(meta) => {
            let what = kind_of(meta.file_type());
            return Err(fail(format!(
                "it is {what}, left as it is (allowed a new or a regular file)"
            )));
        }
        Err(e) if e.kind() == ErrorKind::NotFound => {}
        Err(e) => return Err(fail(io_words(&e))),
    }
    let dir = folder(path);
    match std::fs::metadata(&dir) {
        Ok(meta) if meta.is_dir() => Ok(()),
        Ok(meta) => Err(fail(format!(
            "{} is {}, not a folder",
            shown(&dir),
            kind_of(meta.file_type())
        ))),
        Err(e) if e.kind() == ErrorKind::NotFound => {
            Err(fail(format!("the folder {} does not exist", shown(&dir))))
        }
        Err(e) => Err(fail(format!("{}: {}", shown(&dir), io_words(&e)))),
    }
}

/// Checks that a file can be made in the folder `dir` (which exists), where the output
/// `path` is written: makes a temporary one there and removes it.
fn check_folder_writable(path: &Path, dir: &Path) -> Result<(), FileError> {
    tempfile::NamedTempFile::new_in(dir)
        .map(drop)
        .map_err(|e| no_file_in(path, dir, &e))
}

/// The error of a file at `path` that cannot be written because no file can be made in its
/// folder `dir` (where it is written first, then renamed over `path`).
fn no_file_in(path: &Path, dir: &Path, e: &std::io::Error) -> FileError {
    FileError::new(
        &origin(path),
        None,
        "",
        format!(
            "cannot write: no file can be made in the folder {}: {}",
            shown(dir),
            io_words(e)
        ),
    )
}

/// The folder `path` is in (`.` for a bare file name).
fn folder(path: &Path) -> PathBuf {
    // `Path::new("x").parent()` is the empty path, which the file system does not take.
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Writes `bytes` to `path` atomically, where [`check_output`] allows it: into a temporary
/// file in the same folder, flushed and synced to disk, readable by all like any data file
/// (0644 on Unix; a temporary file starts private), then renamed over `path`. On any error
/// `path` is left as it was and the temporary file is removed.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    check_output(path)?;
    let fail = |e: std::io::Error| {
        FileError::new(
            &origin(path),
            None,
            "",
            format!("cannot write: {}", io_words(&e)),
        )
    };
    let dir = folder(path);
    let mut file = tempfile::NamedTempFile::new_in(&dir).map_err(|e| no_file_in(path, &dir, &e))?;
    file.write_all(bytes).map_err(fail)?;
    file.flush().map_err(fail)?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        file.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(fail)?;
    }
    file.as_file().sync_all().map_err(fail)?;
    file.persist(path).map_err(|e| fail(e.error))?;
    Ok(())
}

/// The files one run reads and writes, each with the flag that names it: declared in one
/// place per command ([`crate::cli::Command::files`]) and checked before the run starts, so
/// that no output replaces an input or another output of the same run.
#[derive(Debug, Default)]
pub struct RunFiles {
    uses: Vec<Use>,
}

/// One file of a run.
#[derive(Debug)]
struct Use {
    /// The flag or argument that names it (`--record`, `FILE`, `--out`).
    flag: String,
    path: PathBuf,
    how: How,
    /// For [`How::Many`]: the names of the files written in the folder `path`.
    named: fn(&str) -> bool,
}

/// What a run does with a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum How {
    Reads,
    Writes,
    /// Writes, in a folder that the run makes if it is missing.
    WritesInto,
    /// Writes files of some names (`frame-000060.png`) into this folder.
    Many,
}

/// Which file a path is: by the OS's identity of it where it exists (links followed, so a
/// link and its target, or two hard links, are one file, and so are a file and itself seen
/// through a bind mount), else by its folder's identity and its name.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    /// A file or folder that is there: the OS's identity of it (device and inode; volume
    /// serial and file index on Windows).
    There(same_file::Handle),
    /// A file not there yet: which folder it would be in, and its name.
    InFolder(same_file::Handle, std::ffi::OsString),
}

impl RunFiles {
    /// No files.
    pub fn new() -> Self {
        RunFiles::default()
    }

    /// The run reads `path`, named by `flag` (nothing when `None`).
    pub fn reads(self, flag: &str, path: Option<&Path>) -> Self {
        self.with(flag, path, How::Reads, |_| false)
    }

    /// The run writes `path`, named by `flag` (nothing when `None`).
    pub fn writes(self, flag: &str, path: Option<&Path>) -> Self {
        self.with(flag, path, How::Writes, |_| false)
    }

    /// The run writes `path` into a folder it makes if missing, named by `flag`.
    pub fn writes_into(self, flag: &str, path: &Path) -> Self {
        self.with(flag, Some(path), How::WritesInto, |_| false)
    }

    /// The run writes files whose names `named` accepts into the folder `dir`, named by
    /// `flag` (nothing when `None`).
    pub fn writes_many(self, flag: &str, dir: Option<&Path>, named: fn(&str) -> bool) -> Self {
        self.with(flag, dir, How::Many, named)
    }

    fn with(mut self, flag: &str, path: Option<&Path>, how: How, named: fn(&str) -> bool) -> Self {
        if let Some(path) = path {
            self.uses.push(Use {
                flag: flag.to_owned(),
                path: path.to_path_buf(),
                how,
                named,
            });
        }
        self
    }

    /// The files read, with their flags.
    pub fn inputs(&self) -> impl Iterator<Item = (&str, &Path)> {
        self.uses_where(|how| how == How::Reads)
    }

    /// The files written, with their flags (not the folders of [`RunFiles::writes_many`]).
    pub fn outputs(&self) -> impl Iterator<Item = (&str, &Path)> {
        self.uses_where(|how| matches!(how, How::Writes | How::WritesInto))
    }

    fn uses_where(&self, keep: impl Fn(How) -> bool) -> impl Iterator<Item = (&str, &Path)> {
        self.uses
            .iter()
            .filter(move |u| keep(u.how))
            .map(|u| (u.flag.as_str(), u.path.as_path()))
    }

    /// Checks, before the run, that every output may be written (see [`check_output`]), in
    /// a folder where a file can be made (so that a run's results are not lost at its end
    /// to a folder it may not write), and that no two uses are one file but where both only
    /// read it: an output that is an input or another output is refused, naming both.
    pub fn check(&self) -> Result<(), FileError> {
        let files = |how: How| matches!(how, How::Writes | How::WritesInto);
        fn flagged(flag: &str) -> impl FnOnce(FileError) -> FileError + '_ {
            move |e| FileError {
                problem: format!("{} ({flag})", e.problem),
                ..e
            }
        }
        for out in self.uses.iter().filter(|u| files(u.how)) {
            if out.how == How::Writes || std::fs::metadata(folder(&out.path)).is_ok() {
                check_output(&out.path).map_err(flagged(&out.flag))?;
                check_folder_writable(&out.path, &folder(&out.path)).map_err(flagged(&out.flag))?;
            }
        }
        for many in self.uses.iter().filter(|u| u.how == How::Many) {
            if std::fs::metadata(&many.path).is_ok_and(|m| m.is_dir()) {
                check_folder_writable(&many.path, &many.path).map_err(flagged(&many.flag))?;
            }
        }
        // A folder's files may land on any other file of the run named like one of them, in
        // that folder however it is reached (a link, a bind mount).
        for many in self.uses.iter().filter(|u| u.how == How::Many) {
            let Some(dir) = identity(&many.path).filter(Identity::exists) else {
                continue;
            };
            let mut others = self.uses.iter().filter(|u| u.how != How::Many);
            let landed = others.find(|u| {
                (u.how != How::Reads || u.path.exists())
                    && real_path(&u.path).is_some_and(|real| {
                        real.parent().and_then(identity).as_ref() == Some(&dir)
                            && real
                                .file_name()
                                .and_then(|name| name.to_str())
                                .is_some_and(many.named)
                    })
            });
            if let Some(other) = landed {
                return Err(FileError::new(
                    &origin(&other.path),
                    None,
                    "",
                    format!(
                        "cannot write ({}): a file it writes would replace {}, named like one \
                         in that folder (give {} another folder)",
                        many.flag, other.flag, many.flag
                    ),
                ));
            }
        }
        // An input that is not there is not read over (reading it fails in its own words).
        let ids: Vec<_> = self
            .uses
            .iter()
            .map(|u| identity(&u.path).filter(|id| u.how != How::Reads || id.exists()))
            .collect();
        for (j, later) in self.uses.iter().enumerate() {
            for (i, earlier) in self.uses[..j].iter().enumerate() {
                let both_read = earlier.how == How::Reads && later.how == How::Reads;
                // A folder of many files is checked above.
                let many = earlier.how == How::Many || later.how == How::Many;
                if both_read || many || ids[i].is_none() || ids[i] != ids[j] {
                    continue;
                }
                let (out, other) = match later.how {
                    How::Reads => (earlier, later),
                    _ => (later, earlier),
                };
                let verb = match other.how {
                    How::Reads => "reads",
                    _ => "writes",
                };
                return Err(FileError::new(
                    &origin(&out.path),
                    None,
                    "",
                    format!(
                        "cannot write ({}): it is the same file as {}, which this run {verb} \
                         (give {} another path)",
                        out.flag, other.flag, out.flag
                    ),
                ));
            }
        }
        Ok(())
    }
}

impl Identity {
    /// Whether the file is there.
    fn exists(&self) -> bool {
        matches!(self, Identity::There(..))
    }
}

/// `path` with its folder's real path (links followed), and itself resolved where it is a
/// link to a file that exists.
fn real_path(path: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(path).ok().or_else(|| {
        let dir = std::fs::canonicalize(folder(path)).ok()?;
        Some(dir.join(path.file_name()?))
    })
}

/// Which file `path` is, when it can be told (a file in a missing folder cannot be). Only
/// files and folders are opened to be told apart: a named pipe would wait for a writer, and
/// what is neither is refused where it is read or written.
fn identity(path: &Path) -> Option<Identity> {
    if let Ok(meta) = std::fs::metadata(path) {
        if !(meta.is_file() || meta.is_dir()) {
            return None;
        }
        return same_file::Handle::from_path(path).ok().map(Identity::There);
    }
    let real = real_path(path)?;
    let dir = same_file::Handle::from_path(real.parent()?).ok()?;
    Some(Identity::InFolder(dir, real.file_name()?.to_owned()))
}
