//! The shape of the sources: no file of the host crate (`host/`) or of the kernels crate
//! (`kernels/src/`) imports itself through other files, no top-level module of either
//! imports itself through other top-level modules, and no file of `host/` is longer than
//! [`MAX_LINES`] lines.
//!
//! What counts as "file A imports file B": A names, in code (not in comments, doc comments
//! or literals), a path that starts with `crate::`, `$crate::`, `super::` or `self::` and
//! leads into B. A path leads into the file of the longest prefix of it that is a module
//! (`crate::game::spec::Scene` into `host/game/spec.rs`; a module written inline, such as
//! `mod tests { .. }`, is part of its file), on through the `pub use` re-exports of that
//! module (`crate::game::Game` into `host/game/engine.rs`); a macro named at the crate root
//! (`crate::kernel_args!`) leads into the file whose `macro_rules!` defines it. Each path of
//! a `use` group (`use crate::a::{b, c::d}`) counts on its own, and the paths in a macro's
//! body count for the file that defines the macro.
//!
//! Not counted: paths that start with a bare name, that is a parent naming its own child
//! module (`mod x; use x::Y;`: a parent declares its parts, while a child's `super::` paths
//! up to it are counted) or another crate; glob re-exports; a file's paths into itself.
//! `host/main.rs` is the binary's own crate root, naming the library as `gpuwars::`: its
//! length is checked, it has no edges.
//!
//! The reading is a tokenizer that skips comments and string and character literals, not a
//! Rust parser: a path that a macro pastes together from pieces is not seen.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::fs;
use std::path::Path;

/// The most lines a file of `host/` may have.
const MAX_LINES: usize = 800;

/// The files of one crate: its source folder and each file's path and text.
struct Crate {
    dir: String,
    files: Vec<(String, String)>,
}

impl Crate {
    /// Every `.rs` file under `dir` (relative to the package root), `skip` left out.
    fn read(dir: &str, skip: &[&str]) -> Crate {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut files = Vec::new();
        let mut folders = vec![root.join(dir)];
        while let Some(folder) = folders.pop() {
            for entry in fs::read_dir(&folder).expect("a source folder") {
                let path = entry.expect("a folder entry").path();
                let rel = path.strip_prefix(root).expect("under the root");
                let rel = rel.to_string_lossy().replace('\\', "/");
                if path.is_dir() {
                    folders.push(path);
                } else if rel.ends_with(".rs") && !skip.contains(&rel.as_str()) {
                    files.push((rel, fs::read_to_string(&path).expect("a source file")));
                }
            }
        }
        files.sort();
        Crate {
            dir: dir.to_owned(),
            files,
        }
    }

    /// The module a file of this crate is: `host/game/mod.rs` and `host/game.rs` are
    /// `game`, `host/lib.rs` the crate root.
    fn module(&self, path: &str) -> Vec<String> {
        let rel = path[self.dir.len() + 1..].trim_end_matches(".rs");
        let mut module: Vec<String> = rel.split('/').map(str::to_owned).collect();
        if matches!(module.last().map(String::as_str), Some("mod" | "lib")) {
            module.pop();
        }
        module
    }
}

/// A token of Rust source, comments and literals left out.
#[derive(Clone, Debug, PartialEq)]
enum Token {
    /// A word: keyword, name or number.
    Word(String),
    /// `::`.
    PathSep,
    /// Any other character.
    Punct(char),
}

/// The tokens of `src`, each with its line.
fn tokens(src: &str) -> Vec<(usize, Token)> {
    let c: Vec<char> = src.chars().collect();
    let at = |i: usize, s: &str| s.chars().enumerate().all(|(k, x)| c.get(i + k) == Some(&x));
    let word_char = |i: usize| c.get(i).is_some_and(|x| x.is_alphanumeric() || *x == '_');
    let (mut i, mut line, mut out) = (0, 1, Vec::new());
    // Skips a string literal whose body starts at `i` and that ends with `"` and `hashes`
    // hashes; escapes only where there are no hashes (a raw string has none).
    let string = |mut i: usize, hashes: usize, line: &mut usize| {
        while i < c.len() {
            if c[i] == '\\' && hashes == 0 {
                i += 1;
            } else if c[i] == '"' && (1..=hashes).all(|k| c.get(i + k) == Some(&'#')) {
                return i + 1 + hashes;
            }
            *line += usize::from(c[i] == '\n');
            i += 1;
        }
        i
    };
    while i < c.len() {
        if at(i, "//") {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if at(i, "/*") {
            let mut depth = 0;
            while i < c.len() {
                if at(i, "/*") {
                    (depth, i) = (depth + 1, i + 2);
                } else if at(i, "*/") {
                    (depth, i) = (depth - 1, i + 2);
                    if depth == 0 {
                        break;
                    }
                } else {
                    line += usize::from(c[i] == '\n');
                    i += 1;
                }
            }
        } else if c[i] == '"' {
            i = string(i + 1, 0, &mut line);
        } else if c[i] == '\'' {
            // A character literal ('x', '\n', '\u{..}'), else a lifetime or a label.
            if c.get(i + 1) == Some(&'\\') {
                // Past the quote, the backslash and the escaped character.
                i += 3;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
            }
        } else if word_char(i) {
            let start = i;
            while word_char(i) {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            let hashes = (i..).take_while(|&k| c.get(k) == Some(&'#')).count();
            match word.as_str() {
                // Raw strings: r"..", r#".."#, and their byte and C forms.
                "r" | "br" | "cr" if c.get(i + hashes) == Some(&'"') => {
                    i = string(i + hashes + 1, hashes, &mut line);
                }
                // A raw identifier: r#type.
                "r" if hashes == 1 => i += 1,
                "b" | "c" if c.get(i) == Some(&'"') => i = string(i + 1, 0, &mut line),
                // A byte: b'x'. The quote is read as a character literal next.
                "b" if c.get(i) == Some(&'\'') => {}
                _ => out.push((line, Token::Word(word))),
            }
        } else if at(i, "::") {
            out.push((line, Token::PathSep));
            i += 2;
        } else {
            line += usize::from(c[i] == '\n');
            if !c[i].is_whitespace() {
                out.push((line, Token::Punct(c[i])));
            }
            i += 1;
        }
    }
    out
}

/// A path and the name it is brought in as (`as`), if any.
type Aliased = (Vec<String>, Option<String>);

/// The paths of the path tree at `i` (`a::b::{c, d::e as f, *}`), and the index after it.
fn tree(t: &[(usize, Token)], mut i: usize) -> (Vec<Aliased>, usize) {
    let word = |i: usize| match t.get(i) {
        Some((_, Token::Word(w))) => Some(w.clone()),
        _ => None,
    };
    let mut prefix = Vec::new();
    loop {
        match t.get(i).map(|(_, token)| token) {
            Some(Token::Word(w)) if w != "as" => prefix.push(w.clone()),
            Some(Token::Punct('*')) => prefix.push("*".to_owned()),
            Some(Token::Punct('{')) => {
                let mut out = Vec::new();
                i += 1;
                while !matches!(t.get(i), Some((_, Token::Punct('}'))) | None) {
                    let (paths, next) = tree(t, i);
                    let paths = paths.into_iter();
                    out.extend(paths.map(|(p, alias)| ([prefix.clone(), p].concat(), alias)));
                    // A token no tree starts with is passed over, so that this ends.
                    i = next.max(i + usize::from(next == i));
                    if matches!(t.get(i), Some((_, Token::Punct(',')))) {
                        i += 1;
                    }
                }
                return (out, i + 1);
            }
            _ => break,
        }
        i += 1;
        if t.get(i).map(|(_, token)| token) != Some(&Token::PathSep) {
            break;
        }
        i += 1;
    }
    let alias = match word(i).as_deref() {
        Some("as") => {
            i += 2;
            word(i - 1)
        }
        _ => None,
    };
    (vec![(prefix, alias)], i)
}

/// What one file says about the module graph.
#[derive(Default)]
struct Said {
    /// Each path that starts with `crate`, `super` or `self`: its line, the inline modules
    /// around it, the path.
    paths: Vec<(usize, Vec<String>, Vec<String>)>,
    /// Each name it re-exports: the inline modules around it, the name, the path.
    reexports: Vec<(Vec<String>, String, Vec<String>)>,
    /// The modules it writes inline, each as the inline modules down to it.
    inline: Vec<Vec<String>>,
    /// The macros it defines.
    macros: Vec<String>,
}

/// Reads what `src` says about the module graph.
fn said(src: &str) -> Said {
    let t = tokens(src);
    let word = |i: usize| match t.get(i) {
        Some((_, Token::Word(w))) => Some(w.as_str()),
        _ => None,
    };
    let punct = |i: usize, p: char| matches!(t.get(i), Some((_, Token::Punct(x))) if *x == p);
    let sep = |i: usize| matches!(t.get(i), Some((_, Token::PathSep)));
    let mut said = Said::default();
    // The inline modules open at `i`, each with the brace depth inside it.
    let (mut open, mut depth, mut i): (Vec<(String, usize)>, usize, usize) = (vec![], 0, 0);
    let scope = |open: &[(String, usize)]| open.iter().map(|(m, _)| m.clone()).collect();
    while i < t.len() {
        if punct(i, '{') {
            depth += 1;
        } else if punct(i, '}') {
            if open.last().is_some_and(|(_, d)| *d == depth) {
                open.pop();
            }
            depth -= 1;
        } else if word(i) == Some("mod") && punct(i + 2, '{') {
            let name = word(i + 1).expect("a module's name").to_owned();
            open.push((name, depth + 1));
            said.inline.push(scope(&open));
            (depth, i) = (depth + 1, i + 3);
            continue;
        } else if word(i) == Some("macro_rules") && punct(i + 1, '!') {
            said.macros.extend(word(i + 2).map(str::to_owned));
        } else if word(i) == Some("pub") {
            // `pub use`, `pub(crate) use`, `pub(in path) use`: a re-export.
            let mut u = i + 1;
            if punct(u, '(') {
                while u < t.len() && !punct(u, ')') {
                    u += 1;
                }
                u += 1;
            }
            if word(u) == Some("use") {
                let (paths, next) = tree(&t, u + 1);
                for (mut path, alias) in paths {
                    if path.last().map(String::as_str) == Some("self") {
                        path.pop();
                    }
                    let name = alias.or_else(|| path.last().cloned());
                    match name {
                        Some(name) if name != "*" => {
                            said.reexports.push((scope(&open), name, path.clone()));
                        }
                        _ => {}
                    }
                    if matches!(
                        path.first().map(String::as_str),
                        Some("crate" | "super" | "self")
                    ) {
                        said.paths.push((t[u].0, scope(&open), path));
                    }
                }
                i = next;
                continue;
            }
        } else if matches!(word(i), Some("crate" | "super" | "self"))
            && sep(i + 1)
            && !(i > 0 && sep(i - 1))
        {
            let (paths, next) = tree(&t, i);
            for (path, _) in paths {
                said.paths.push((t[i].0, scope(&open), path));
            }
            i = next;
            continue;
        }
        i += 1;
    }
    said
}

/// The graph of the files of some crates.
struct Graph {
    /// Each file's path.
    files: Vec<String>,
    /// Each file's crate and top-level module (empty for the crate root), as `crate:module`.
    tops: Vec<String>,
    /// File edges, each with where it was first seen (`line: path`).
    edges: BTreeMap<(usize, usize), String>,
}

/// The graph of `crates`' files (see the module's documentation for what counts).
fn graph(crates: &[Crate]) -> Graph {
    let mut files = Vec::new();
    let mut tops = Vec::new();
    // Per crate: each module's file, each re-export's path, each macro's file.
    let mut modules = BTreeMap::new();
    let mut reexports = BTreeMap::new();
    let mut macros = BTreeMap::new();
    let mut all_said = Vec::new();
    for (k, krate) in crates.iter().enumerate() {
        for (path, text) in &krate.files {
            let file = files.len();
            let module = krate.module(path);
            let top = module.first().cloned().unwrap_or_default();
            files.push(path.clone());
            tops.push(format!("{}:{top}", krate.dir));
            let said = said(text);
            modules.insert((k, module.clone()), file);
            for inline in &said.inline {
                modules.insert((k, [module.clone(), inline.clone()].concat()), file);
            }
            for name in &said.macros {
                macros.entry((k, name.clone())).or_insert(file);
            }
            all_said.push((k, file, module, said));
        }
    }
    // A path made absolute from where it is written, `None` when it leaves the crate.
    let absolute = |k: usize, here: &[String], path: &[String]| {
        let mut out = here.to_vec();
        let mut rest = path;
        match path.first().map(String::as_str) {
            Some("crate") => (out, rest) = (vec![], &path[1..]),
            Some("super" | "self") => {}
            // A bare path is a child module of `here`, or another crate.
            _ if modules.contains_key(&(k, [here, &path[..1]].concat())) => {}
            _ => return None,
        }
        while let Some(first) = rest.first() {
            match first.as_str() {
                "super" => {
                    out.pop();
                }
                "self" => {}
                _ => break,
            }
            rest = &rest[1..];
        }
        out.extend(rest.iter().filter(|s| *s != "self").cloned());
        Some(out)
    };
    for (k, _, module, said) in &all_said {
        for (scope, name, path) in &said.reexports {
            let here = [module.clone(), scope.clone()].concat();
            if let Some(target) = absolute(*k, &here, path) {
                reexports.insert((*k, here, name.clone()), target);
            }
        }
    }
    // The file a path leads into: the longest module prefix, through re-exports and macros.
    let resolve = |k: usize, path: Vec<String>| {
        let mut path = path;
        for _ in 0..16 {
            let prefix = (0..=path.len())
                .rev()
                .find(|&n| modules.contains_key(&(k, path[..n].to_vec())))
                .expect("the crate root is a module");
            let file = modules[&(k, path[..prefix].to_vec())];
            let Some(name) = path.get(prefix) else {
                return file;
            };
            if let Some(target) = reexports.get(&(k, path[..prefix].to_vec(), name.clone())) {
                path = [target.clone(), path[prefix + 1..].to_vec()].concat();
            } else if prefix == 0 && macros.contains_key(&(k, name.clone())) {
                return macros[&(k, name.clone())];
            } else {
                return file;
            }
        }
        panic!("re-exports in a loop at {path:?}");
    };
    let mut edges = BTreeMap::new();
    for (k, file, module, said) in &all_said {
        for (line, scope, path) in &said.paths {
            let here = [module.clone(), scope.clone()].concat();
            let Some(target) = absolute(*k, &here, path) else {
                continue;
            };
            let to = resolve(*k, target);
            if to != *file {
                edges
                    .entry((*file, to))
                    .or_insert_with(|| format!("line {line}: {}", path.join("::")));
            }
        }
    }
    Graph { files, tops, edges }
}

/// Cycles that name the loops of `edges`: for each node, the shortest cycle through it (each
/// cycle once, starting from its smallest node).
fn cycles(nodes: usize, edges: &BTreeSet<(usize, usize)>) -> Vec<Vec<usize>> {
    let next = |n: usize| edges.range((n, 0)..(n + 1, 0)).map(|&(_, to)| to);
    let mut out = BTreeSet::new();
    for start in 0..nodes {
        // Breadth first from `start` until an edge leads back to it.
        let mut from = BTreeMap::new();
        let mut queue = VecDeque::from([start]);
        'search: while let Some(n) = queue.pop_front() {
            for to in next(n) {
                if to == start {
                    let mut cycle = vec![n];
                    while let Some(&before) = from.get(cycle.last().expect("a node")) {
                        cycle.push(before);
                    }
                    cycle.reverse();
                    let smallest = (0..cycle.len()).min_by_key(|&i| cycle[i]).expect("a node");
                    cycle.rotate_left(smallest);
                    out.insert(cycle);
                    break 'search;
                }
                if let std::collections::btree_map::Entry::Vacant(e) = from.entry(to) {
                    e.insert(n);
                    queue.push_back(to);
                }
            }
        }
    }
    out.into_iter().collect()
}

/// Each cycle of files in `g`, as lines `a -> b (line: path) -> ... -> a`.
fn file_cycles(g: &Graph) -> Vec<String> {
    let edges = g.edges.keys().copied().collect();
    cycles(g.files.len(), &edges)
        .into_iter()
        .map(|cycle| {
            let mut text = g.files[cycle[0]].clone();
            for (i, &from) in cycle.iter().enumerate() {
                let to = cycle[(i + 1) % cycle.len()];
                text += &format!(" -> {} ({})", g.files[to], g.edges[&(from, to)]);
            }
            text
        })
        .collect()
}

/// Each cycle of top-level modules in `g`, as lines `a -> b (file -> file, line: path)
/// -> ... -> a`.
fn top_cycles(g: &Graph) -> Vec<String> {
    let names: Vec<&String> = g.tops.iter().collect::<BTreeSet<_>>().into_iter().collect();
    let index = |file: usize| names.binary_search(&&g.tops[file]).expect("a top");
    let mut why = BTreeMap::new();
    for (&(from, to), seen) in &g.edges {
        if index(from) != index(to) {
            why.entry((index(from), index(to)))
                .or_insert_with(|| format!("{} -> {}, {seen}", g.files[from], g.files[to]));
        }
    }
    let edges = why.keys().copied().collect();
    cycles(names.len(), &edges)
        .into_iter()
        .map(|cycle| {
            let mut text = names[cycle[0]].clone();
            for (i, &from) in cycle.iter().enumerate() {
                let to = cycle[(i + 1) % cycle.len()];
                text += &format!(" -> {} ({})", names[to], why[&(from, to)]);
            }
            text
        })
        .collect()
}

/// Both crates' sources, the binary's root left out.
fn sources() -> Vec<Crate> {
    vec![
        Crate::read("host", &["host/main.rs"]),
        Crate::read("kernels/src", &[]),
    ]
}

#[test]
fn no_file_imports_itself_through_others() {
    let found = file_cycles(&graph(&sources()));
    assert!(
        found.is_empty(),
        "files that import each other:\n{}",
        found.join("\n")
    );
}

#[test]
fn no_top_level_module_imports_itself_through_others() {
    let found = top_cycles(&graph(&sources()));
    assert!(
        found.is_empty(),
        "modules that import each other:\n{}",
        found.join("\n")
    );
}

#[test]
fn no_host_file_is_too_long() {
    let host = Crate::read("host", &[]);
    let long: Vec<String> = (host.files.iter())
        .map(|(path, text)| (path, text.lines().count()))
        .filter(|&(_, lines)| lines > MAX_LINES)
        .map(|(path, lines)| format!("{path}: {lines} lines"))
        .collect();
    assert!(
        long.is_empty(),
        "over {MAX_LINES} lines:\n{}",
        long.join("\n")
    );
}

/// The check itself, on made-up files: what it counts, what it leaves out, and that it
/// names a cycle.
#[test]
fn the_check_counts_what_it_says() {
    let files = [
        (
            "x/lib.rs",
            "pub mod a;\npub mod b;\npub mod c;\npub mod d;\n",
        ),
        (
            "x/a/mod.rs",
            "mod inner;\npub use inner::Thing;\n\
             use inner::Other; // a bare path: not counted\n",
        ),
        (
            "x/a/inner.rs",
            "use super::super::d; // counted\n\
             /// [`crate::c::X`] in a doc link: not counted\n\
             pub struct Thing;\npub struct Other;\n",
        ),
        (
            "x/b.rs",
            "use crate::{a::{self, Thing}, c};\n\
             const S: &str = \"crate::d::X\";\n\
             macro_rules! m { () => {} }\n",
        ),
        (
            "x/c.rs",
            "fn f() -> char { let _ = r#\"crate::d\"#; '\"' }\n\
             mod tests { use super::f; fn g() { crate::m!(); } }\n",
        ),
        ("x/d.rs", "pub struct X;\n"),
    ];
    let krate = Crate {
        dir: "x".into(),
        files: files.map(|(p, t)| (p.into(), t.into())).to_vec(),
    };
    let g = graph(&[krate]);
    let named: BTreeSet<(&str, &str)> = (g.edges.keys())
        .map(|&(a, b)| (g.files[a].as_str(), g.files[b].as_str()))
        .collect();
    let expected = BTreeSet::from([
        ("x/a/inner.rs", "x/d.rs"),
        // `a::Thing` through the re-export, `a` itself through `self`.
        ("x/b.rs", "x/a/inner.rs"),
        ("x/b.rs", "x/a/mod.rs"),
        ("x/b.rs", "x/c.rs"),
        // The macro, from an inline module; its `super::f` is the file's own.
        ("x/c.rs", "x/b.rs"),
    ]);
    assert_eq!(named, expected);
    assert!(
        file_cycles(&g).contains(
            &"x/b.rs -> x/c.rs (line 1: crate::c) -> x/b.rs (line 2: crate::m)".to_owned()
        ),
        "{:?}",
        file_cycles(&g)
    );
    assert_eq!(top_cycles(&g).len(), 1, "{:?}", top_cycles(&g));
}
