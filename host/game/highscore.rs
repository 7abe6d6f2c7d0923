//! The best score of each scene, kept in a TOML file in the user's data directory:
//!
//! ```toml
//! [scenes.paper]
//! score = 1234
//! when = 1767225600
//! seed = 1
//! ```
//!
//! Scene names are table keys, quoted as TOML needs (`[scenes."my.scene"]`), so any name
//! reads back as it was. A file that does not read is reported, treated as empty, and
//! replaced on the next save: losing the scores beats refusing to play.

use std::collections::BTreeMap;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

use crate::files::{FileError, excerpt, line_of, read_text, thousands};

/// The environment variable that, when set and not empty, names the directory of the file
/// instead of the user's data directory.
pub const DATA_DIR_VAR: &str = "GPUWARS_DATA_DIR";
/// The file's name in its directory.
pub const FILE_NAME: &str = "highscores.toml";

/// Most bytes of the file: far more than the scores of every scene take.
const MAX_BYTES: u64 = 1 << 20;

/// Written at the top of the file.
const HEADER: &str =
    "# GpuWars high scores: the best score of each scene. The game rewrites this file.\n\n";

/// A scene's best game.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Entry {
    /// The score.
    pub score: u32,
    /// When it was played, in seconds since the Unix epoch.
    pub when: u64,
    /// The game's random seed, when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u32>,
}

/// The best score of each scene, and the file they are saved to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HighScores {
    path: PathBuf,
    scenes: BTreeMap<String, Entry>,
}

/// The file as written.
#[derive(Default, Serialize, Deserialize)]
struct Stored {
    #[serde(default)]
    scenes: BTreeMap<String, Entry>,
}

/// `highscores.toml` in the directory named by [`DATA_DIR_VAR`], else in the user's data
/// directory for gpuwars (`~/.local/share/gpuwars` on Linux); `None` when the system names no
/// home directory.
pub fn default_path() -> Option<PathBuf> {
    let dir = match std::env::var_os(DATA_DIR_VAR) {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => directories::ProjectDirs::from("", "", "gpuwars")?
            .data_dir()
            .to_path_buf(),
    };
    Some(dir.join(FILE_NAME))
}

impl HighScores {
    /// Reads the scores at `path`. A missing file (or directory) holds none. A file that cannot
    /// be read or does not parse (not UTF-8, not TOML, a wrong type, a negative number, a
    /// directory in its place) also gives none, with the warning to show: the next
    /// [`HighScores::save`] replaces it.
    pub fn load(path: impl Into<PathBuf>) -> (HighScores, Option<FileError>) {
        let path = path.into();
        let (scenes, warning) = match read(&path) {
            Ok(scenes) => (scenes, None),
            Err(e) => (BTreeMap::new(), Some(e)),
        };
        (HighScores { path, scenes }, warning)
    }

    /// The file the scores are saved to.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The best game of `scene`, if one was recorded.
    pub fn best(&self, scene: &str) -> Option<Entry> {
        self.scenes.get(scene).copied()
    }

    /// Records a game of `scene` played now; returns whether it is the scene's new best (the
    /// first game, or a score above the best: a tie keeps the earlier game). Only in memory
    /// until [`HighScores::save`].
    pub fn record(&mut self, scene: &str, score: u32, seed: Option<u32>) -> bool {
        if self.best(scene).is_some_and(|best| score <= best.score) {
            return false;
        }
        // A clock before 1970 is wrong, not a reason to lose the score.
        let when = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        let entry = Entry { score, when, seed };
        self.scenes.insert(scene.to_owned(), entry);
        true
    }

    /// Writes the file atomically (see [`crate::files::write_atomically`]), creating its
    /// directory if needed; the error names the path and what failed.
    pub fn save(&self) -> Result<(), FileError> {
        let origin = self.path.display().to_string();
        let fail = |problem: String| FileError::new(&origin, None, "", problem);
        let stored = Stored {
            scenes: self.scenes.clone(),
        };
        let body =
            toml::to_string(&stored).map_err(|e| fail(format!("cannot encode the scores: {e}")))?;
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| {
                fail(format!(
                    "cannot create the directory {}: {e}",
                    dir.display()
                ))
            })?;
        }
        crate::files::write_atomically(&self.path, format!("{HEADER}{body}").as_bytes())
    }
}

/// The scenes in the file at `path`: none if it does not exist.
fn read(path: &Path) -> Result<BTreeMap<String, Entry>, FileError> {
    let origin = path.display().to_string();
    if let Err(e) = std::fs::metadata(path)
        && e.kind() == ErrorKind::NotFound
    {
        return Ok(BTreeMap::new());
    }
    let afresh = |e: FileError| FileError {
        problem: format!("{}; starting afresh", e.problem),
        ..e
    };
    let text = read_text(path, MAX_BYTES).map_err(afresh)?;
    let stored: Stored = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|span| line_of(text.as_bytes(), span.start));
        afresh(FileError::new(
            &origin,
            line,
            "",
            reword(e.message().trim_end()),
        ))
    })?;
    Ok(stored.scenes)
}

/// A message of serde's (through the toml crate) in the file's terms: `expected u32`
/// becomes what a score may be, `map` a table, `missing field` a missing key.
fn reword(message: &str) -> String {
    let words = |text: &str| {
        let text = text.replace(" as i128", "");
        match text.as_str() {
            "u32" | "u64" => {
                let max = if text == "u32" {
                    u64::from(u32::MAX)
                } else {
                    u64::MAX
                };
                format!("a whole number from 0 to {}", thousands(max))
            }
            "map" | "a map" => "a table".to_owned(),
            "sequence" | "a sequence" => "an array".to_owned(),
            other if other.starts_with("struct ") => "a table".to_owned(),
            // `integer `-3``, `string "lots"`: the value as written.
            other => match other.split_once(' ') {
                Some((_, value)) => excerpt(value.trim_matches('`')),
                None => excerpt(other),
            },
        }
    };
    let found_expected = message
        .strip_prefix("invalid type: ")
        .or_else(|| message.strip_prefix("invalid value: "))
        .and_then(|rest| rest.split_once(", expected "));
    if let Some((found, expected)) = found_expected {
        return format!("expected {}, found {}", words(expected), words(found));
    }
    match message.strip_prefix("missing field ") {
        Some(key) => format!("missing key {key}"),
        None => message.to_owned(),
    }
}
