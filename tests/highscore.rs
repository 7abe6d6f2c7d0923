//! High scores: the round trip (any scene name), new bests, and files that do not read
//! (reported, then replaced), never a panic. Every file lives in a temporary directory.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{SystemTime, UNIX_EPOCH};

use gpuwars::game::highscore::{DATA_DIR_VAR, Entry, FILE_NAME, HighScores, default_path};
use proptest::prelude::*;

fn file_in(dir: &Path) -> PathBuf {
    dir.join(FILE_NAME)
}

/// Loads `path`, which must read without a warning.
fn load_clean(path: &Path) -> HighScores {
    let (scores, warning) = HighScores::load(path);
    assert_eq!(warning, None);
    scores
}

fn now() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs()
}

#[test]
fn missing_file_is_empty() {
    let dir = tempfile::tempdir().unwrap();
    let scores = load_clean(&file_in(dir.path()));
    assert_eq!(scores.best("paper"), None);
    assert_eq!(scores.path(), file_in(dir.path()));
}

#[test]
fn round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = file_in(dir.path());
    let (before, after) = (now(), now() + 1);
    let mut scores = load_clean(&path);
    assert!(scores.record("paper", 1234, Some(7)));
    assert!(scores.record("swarm", 99, None));
    scores.save().unwrap();

    let read = load_clean(&path);
    assert_eq!(read, scores);
    let paper = read.best("paper").unwrap();
    assert_eq!((paper.score, paper.seed), (1234, Some(7)));
    assert!(
        (before..=after).contains(&paper.when),
        "when {}",
        paper.when
    );
    assert_eq!(read.best("swarm").unwrap().seed, None);
    assert_eq!(read.best("other"), None);
    // The file is plain TOML a person can read.
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.contains("[scenes.paper]") && text.contains("score = 1234"),
        "{text}"
    );
}

#[test]
fn only_a_higher_score_is_a_new_best() {
    let dir = tempfile::tempdir().unwrap();
    let mut scores = load_clean(&file_in(dir.path()));
    assert!(
        scores.record("paper", 0, None),
        "the first game is the best yet"
    );
    assert!(scores.record("paper", 10, Some(1)));
    assert!(
        !scores.record("paper", 10, Some(2)),
        "a tie keeps the first"
    );
    assert!(!scores.record("paper", 9, Some(3)));
    assert_eq!(scores.best("paper").unwrap().seed, Some(1));
    assert!(scores.record("paper", 11, Some(4)));
    assert_eq!(scores.best("paper").unwrap().score, 11);
    // Scenes are kept apart.
    assert!(scores.record("swarm", 1, None));
    assert_eq!(scores.best("paper").unwrap().score, 11);
}

/// A broken file: loads empty with a warning naming the file (and the line when it is one
/// line's fault), and the next save replaces it with a good one.
fn assert_reported_and_replaced(contents: &[u8], line: Option<usize>, problem: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = file_in(dir.path());
    std::fs::write(&path, contents).unwrap();
    let (mut scores, warning) = HighScores::load(&path);
    let warning = warning.expect("a warning");
    assert_eq!(warning.file, path.display().to_string());
    assert_eq!(warning.line, line, "{warning}");
    assert!(warning.problem.contains(problem), "{warning}");
    for rust in [
        "u32",
        "u64",
        "i128",
        "invalid type",
        "invalid value",
        "map",
        "struct",
    ] {
        assert!(
            !warning.problem.contains(rust),
            "{warning} speaks of `{rust}`"
        );
    }
    assert!(warning.to_string().starts_with(&warning.file));
    assert_eq!(scores.best("paper"), None);

    assert!(scores.record("paper", 5, None));
    scores.save().unwrap();
    assert_eq!(load_clean(&path).best("paper").unwrap().score, 5);
}

#[test]
fn corrupt_files_are_reported_and_replaced() {
    assert_reported_and_replaced(b"[scenes.paper\nscore = 1\n", Some(1), "");
    assert_reported_and_replaced(
        b"[scenes.paper]\nscore = \"lots\"\nwhen = 1\n",
        Some(2),
        "expected a whole number from 0 to 4,294,967,295, found \"lots\"",
    );
    assert_reported_and_replaced(
        b"[scenes.paper]\nscore = -3\nwhen = 1\n",
        Some(2),
        "expected a whole number from 0 to 4,294,967,295, found -3",
    );
    assert_reported_and_replaced(
        b"[scenes.paper]\nscore = 4294967296\nwhen = 1\n",
        Some(2),
        "found 4294967296",
    );
    assert_reported_and_replaced(
        b"[scenes.paper]\nscore = 1\nwhen = -1\n",
        Some(3),
        "expected a whole number from 0 to 18,446,744,073,709,551,615, found -1",
    );
    assert_reported_and_replaced(
        b"[scenes.paper]\nwhen = 1\n",
        Some(1),
        "missing key `score`",
    );
    assert_reported_and_replaced(b"scenes = 3\n", Some(1), "expected a table, found 3");
    assert_reported_and_replaced(
        b"[scenes.paper]\nscore = 99999999999999999999\nwhen = 1\n",
        Some(2),
        "found 99999999999999999999",
    );
    assert_reported_and_replaced(b"# ok\n\xff\xfe\n", Some(2), "not UTF-8");
}

#[test]
fn unknown_keys_are_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let path = file_in(dir.path());
    let text = "version = 9\n[scenes.paper]\nscore = 3\nwhen = 4\nnote = \"x\"\n";
    std::fs::write(&path, text).unwrap();
    let scores = load_clean(&path);
    let expected = Entry {
        score: 3,
        when: 4,
        seed: None,
    };
    assert_eq!(scores.best("paper"), Some(expected));
}

#[test]
fn missing_directories_are_created() {
    let dir = tempfile::tempdir().unwrap();
    let path = file_in(&dir.path().join("a").join("b"));
    let mut scores = load_clean(&path);
    scores.record("paper", 1, None);
    scores.save().unwrap();
    assert_eq!(load_clean(&path).best("paper").unwrap().score, 1);
}

#[test]
fn a_directory_in_place_of_the_file_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = file_in(dir.path());
    std::fs::create_dir(&path).unwrap();
    std::fs::write(path.join("keep"), "").unwrap();
    let (mut scores, warning) = HighScores::load(&path);
    let warning = warning.expect("a warning");
    assert!(warning.problem.contains("cannot read"), "{warning}");
    scores.record("paper", 1, None);
    let error = scores.save().unwrap_err();
    assert_eq!(error.file, path.display().to_string());
    assert!(error.problem.contains("cannot write"), "{error}");
    assert!(path.join("keep").exists(), "the directory is left alone");
    // Nothing but the directory is left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn a_directory_that_cannot_be_made_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, "").unwrap();
    let path = file_in(&blocker.join("sub"));
    let (mut scores, warning) = HighScores::load(&path);
    // Reading through a file is an error of its own (not a missing file) where the system
    // tells them apart: Unix says "not a directory", Windows "path not found".
    assert!(warning.is_some() || cfg!(not(unix)));
    scores.record("paper", 1, None);
    let error = scores.save().unwrap_err();
    assert!(
        error.problem.contains("cannot create the directory"),
        "{error}"
    );
}

/// [`DATA_DIR_VAR`] picks the directory. Checked in a child process (this test binary, running
/// only [`print_default_path`]): setting a variable in this multi-threaded one is unsound.
#[test]
fn data_dir_variable() {
    let dir = tempfile::tempdir().unwrap();
    let exe = std::env::current_exe().unwrap();
    let run = |value: &Path| {
        let out = Command::new(&exe)
            .args(["--exact", "print_default_path", "--ignored", "--nocapture"])
            .env(DATA_DIR_VAR, value)
            .output()
            .unwrap();
        assert!(out.status.success());
        String::from_utf8(out.stdout).unwrap()
    };
    let expected = format!("default path: {}\n", file_in(dir.path()).display());
    assert!(run(dir.path()).contains(&expected));
    // Empty is unset: the user's data directory.
    assert!(!run(Path::new("")).contains(&expected));
}

#[test]
#[ignore = "run by data_dir_variable"]
fn print_default_path() {
    if let Some(path) = default_path() {
        println!("default path: {}", path.display());
    }
}

/// Printable text of any script, or short names made of what TOML must quote or escape.
fn scene_name() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<String>(),
        r#"[\x00-\x1f\x7f"'.\[\]= #\\aé日🎮]{0,12}"#,
    ]
}

#[test]
fn tricky_names_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = file_in(dir.path());
    let names = [
        "",
        "a.b",
        "\"quoted\"",
        "[scenes]",
        "日本",
        "tab\tnew\nline",
        "\0",
        "é",
    ];
    let mut scores = load_clean(&path);
    for (score, name) in (1..).zip(names) {
        assert!(scores.record(name, score, Some(score)));
    }
    scores.save().unwrap();
    let read = load_clean(&path);
    for (score, name) in (1..).zip(names) {
        assert_eq!(read.best(name).map(|e| e.score), Some(score), "{name:?}");
    }
}

proptest! {
    /// Any scene names (quotes, dots, brackets, escapes, control characters, unicode, empty)
    /// and scores read back as saved.
    #[test]
    fn any_names_round_trip(
        games in prop::collection::vec(
            (scene_name(), any::<u32>(), any::<Option<u32>>()),
            0..8,
        ),
    ) {
        let dir = tempfile::tempdir().unwrap();
        let path = file_in(dir.path());
        let mut scores = HighScores::load(&path).0;
        for (scene, score, seed) in &games {
            scores.record(scene, *score, *seed);
        }
        scores.save().unwrap();
        let (read, warning) = HighScores::load(&path);
        prop_assert_eq!(warning, None);
        prop_assert_eq!(&read, &scores);
        for (scene, _, _) in &games {
            let best = games.iter().filter(|g| &g.0 == scene).map(|g| g.1).max();
            prop_assert_eq!(read.best(scene).map(|e| e.score), best);
        }
    }
}
