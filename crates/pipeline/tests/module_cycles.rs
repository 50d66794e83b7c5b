//! No import circle between the files of a crate (issue 26): for every crate of the
//! workspace (`crates/*/src`, and `crates/cli`), the files are the nodes of a graph with an
//! edge `a.rs → b.rs` when `a.rs` names an item of `b.rs` (`use crate::b::...`,
//! `use super::...`, a child module's path, or `crate::b::f(...)` in code), and the graph
//! must have no cycle. Re-exports are followed to the file that defines the item (a crate
//! root's `pub use b::X` makes `crate::X` an edge to `b.rs`), and a crate root's own
//! `pub use` lines are its façade, not edges. Comments, string literals and `#[cfg(test)]`
//! items do not count.
//!
//! In bodyseg-pipeline, besides, no command module uses another: shared helpers live in
//! non-command modules.
//!
//! The checker is a small Rust lexer and `use`-tree parser, no dependency; its own tests
//! plant cycles in temporary crates and must find them.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// bodyseg-pipeline's command modules (one per `bodyseg` command), which must not use one
/// another.
const PIPELINE_COMMANDS: [&str; 13] = [
    "boxes",
    "calibrate",
    "convert",
    "eval",
    "import_ros2",
    "import_cloud",
    "parse",
    "project",
    "refine",
    "rig",
    "run",
    "synth",
    "view",
];

#[derive(Clone, Debug, PartialEq)]
enum Token {
    Ident(String),
    /// `::`
    Path,
    /// Any other punctuation character.
    Punct(char),
    /// A string, char or number literal (its content dropped).
    Literal,
}

/// The tokens of Rust source, without comments; literals' contents dropped.
fn lex(src: &str) -> Vec<Token> {
    let c: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        let next = c.get(i + 1).copied();
        if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && next == Some('*') {
            // Block comments nest.
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if raw_string_at(&c, i) || (ch == 'b' && raw_string_at(&c, i + 1)) {
            // Raw string: r#"..."# with as many #s.
            let start = if ch == 'b' { i + 2 } else { i + 1 };
            let hashes = c[start..].iter().take_while(|&&x| x == '#').count();
            i = start + hashes + 1;
            while i < c.len() {
                let closes = c[i + 1..].len() >= hashes
                    && c[i + 1..i + 1 + hashes].iter().all(|&x| x == '#');
                if c[i] == '"' && closes {
                    i += 1 + hashes;
                    break;
                }
                i += 1;
            }
            out.push(Token::Literal);
        } else if ch == '"' || (ch == 'b' && next == Some('"')) {
            i += if ch == 'b' { 2 } else { 1 };
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push(Token::Literal);
        } else if ch == '\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime ('a).
            if next == Some('\\') {
                // Past the quote, the backslash and the escaped character.
                i += 3;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
                out.push(Token::Literal);
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
                out.push(Token::Literal);
            } else {
                i += 1;
                while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                    i += 1;
                }
            }
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(Token::Ident(c[start..i].iter().collect()));
        } else if ch.is_ascii_digit() {
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_' || c[i] == '.') {
                // `1..n` is a range, not a number.
                if c[i] == '.' && c.get(i + 1) == Some(&'.') {
                    break;
                }
                i += 1;
            }
            out.push(Token::Literal);
        } else if ch == ':' && next == Some(':') {
            out.push(Token::Path);
            i += 2;
        } else {
            out.push(Token::Punct(ch));
            i += 1;
        }
    }
    out
}

/// Whether a raw string (`r"`, `r#"`, `r##"` ...) starts at `c[i]` (the `r`).
fn raw_string_at(c: &[char], i: usize) -> bool {
    if c.get(i) != Some(&'r') {
        return false;
    }
    let hashes = c[i + 1..].iter().take_while(|&&x| x == '#').count();
    c.get(i + 1 + hashes) == Some(&'"')
}

fn ident(t: Option<&Token>) -> Option<&str> {
    match t {
        Some(Token::Ident(s)) => Some(s),
        _ => None,
    }
}

/// Drops every item marked `#[cfg(test)]` (test modules, test-only imports).
fn drop_test_items(tokens: Vec<Token>) -> Vec<Token> {
    let attr = [
        Token::Punct('#'),
        Token::Punct('['),
        Token::Ident("cfg".into()),
        Token::Punct('('),
        Token::Ident("test".into()),
        Token::Punct(')'),
        Token::Punct(']'),
    ];
    let mut out = Vec::with_capacity(tokens.len());
    let mut i = 0;
    while i < tokens.len() {
        if tokens[i..].starts_with(&attr) {
            // Skip the item: up to its `;`, or to the brace that closes its first block.
            i += attr.len();
            let mut depth = 0usize;
            while i < tokens.len() {
                match &tokens[i] {
                    Token::Punct('{') => depth += 1,
                    Token::Punct('}') => {
                        depth = depth.saturating_sub(1);
                        if depth == 0 {
                            i += 1;
                            break;
                        }
                    }
                    Token::Punct(';') if depth == 0 => {
                        i += 1;
                        break;
                    }
                    _ => {}
                }
                i += 1;
            }
        } else {
            out.push(tokens[i].clone());
            i += 1;
        }
    }
    out
}

/// One path of a `use` tree: its segments and the name it binds (`None` for a glob).
#[derive(Clone, Debug, PartialEq)]
struct UsePath {
    segments: Vec<String>,
    name: Option<String>,
}

/// Parses a `use` tree starting at `tokens[*i]` with `prefix` already read; stops before
/// the `,`, `}` or `;` that ends it.
fn parse_use_tree(tokens: &[Token], i: &mut usize, prefix: Vec<String>, out: &mut Vec<UsePath>) {
    let mut segments = prefix;
    loop {
        match tokens.get(*i) {
            Some(Token::Ident(s)) if s == "as" => {
                *i += 1;
                let name = ident(tokens.get(*i)).map(str::to_string);
                *i += 1;
                out.push(UsePath { segments, name });
                return;
            }
            Some(Token::Ident(s)) => {
                segments.push(s.clone());
                *i += 1;
            }
            Some(Token::Path) => *i += 1,
            Some(Token::Punct('*')) => {
                *i += 1;
                out.push(UsePath {
                    segments,
                    name: None,
                });
                return;
            }
            Some(Token::Punct('{')) => {
                *i += 1;
                loop {
                    match tokens.get(*i) {
                        Some(Token::Punct('}')) => {
                            *i += 1;
                            return;
                        }
                        Some(Token::Punct(',')) => *i += 1,
                        None => return,
                        _ => parse_use_tree(tokens, i, segments.clone(), out),
                    }
                }
            }
            _ => {
                // `self` in a group names the group's path itself.
                if segments.last().is_some_and(|s| s == "self") {
                    segments.pop();
                }
                let name = segments.last().cloned();
                out.push(UsePath { segments, name });
                return;
            }
        }
    }
}

/// A source file of a crate.
#[derive(Clone, Debug)]
struct SourceFile {
    /// Path relative to the crate's source root, for messages (`recording.rs`).
    name: String,
    /// Its module path (`[]` for the crate root, `["find", "heads"]`).
    module: Vec<String>,
    tokens: Vec<Token>,
}

/// Whether the `use` at `tokens[i]` is a re-export: `pub use`, `pub(crate) use`,
/// `pub(super) use`, `pub(in path) use`.
fn is_public_use(tokens: &[Token], i: usize) -> bool {
    match i.checked_sub(1).map(|k| &tokens[k]) {
        Some(Token::Ident(s)) => s == "pub",
        Some(Token::Punct(')')) => {
            let open = (0..i - 1).rev().find(|&k| tokens[k] == Token::Punct('('));
            open.and_then(|k| k.checked_sub(1))
                .is_some_and(|k| ident(tokens.get(k)) == Some("pub"))
        }
        _ => false,
    }
}

/// The `use` declarations of a file: (re-export, path) for each path of each tree, and a
/// mask of the tokens inside them.
fn use_paths(tokens: &[Token]) -> (Vec<(bool, UsePath)>, Vec<bool>) {
    let mut out = Vec::new();
    let mut in_use = vec![false; tokens.len()];
    let mut i = 0;
    while i < tokens.len() {
        if ident(tokens.get(i)) == Some("use") {
            let public = is_public_use(tokens, i);
            let start = i;
            let mut paths = Vec::new();
            i += 1;
            parse_use_tree(tokens, &mut i, Vec::new(), &mut paths);
            for flag in &mut in_use[start..i.min(tokens.len())] {
                *flag = true;
            }
            out.extend(paths.into_iter().map(|p| (public, p)));
        } else {
            i += 1;
        }
    }
    (out, in_use)
}

/// The files of the crate whose source root (the folder of `lib.rs` or `main.rs`) is
/// `root`.
fn read_crate(root: &Path) -> Vec<SourceFile> {
    let mut files = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                // Binaries under src/bin are crates of their own.
                if path != root.join("bin") {
                    stack.push(path);
                }
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let relative = path.strip_prefix(root).unwrap_or(&path);
            let mut module: Vec<String> = relative
                .with_extension("")
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            let is_root = module == ["lib"] || module == ["main"];
            let is_mod = module.last().is_some_and(|m| m == "mod");
            if is_root || is_mod {
                module.pop();
            }
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            files.push(SourceFile {
                name: relative.display().to_string(),
                module,
                tokens: drop_test_items(lex(&text)),
            });
        }
    }
    files.sort_by(|a, b| a.name.cmp(&b.name));
    files
}

/// The edges between the files of one crate: `edges[a]` = the files `a` depends on.
fn file_graph(files: &[SourceFile]) -> BTreeMap<String, BTreeSet<String>> {
    let by_module: BTreeMap<&[String], &SourceFile> =
        files.iter().map(|f| (f.module.as_slice(), f)).collect();
    // Every file's re-exports: (module, bound name) → absolute path.
    let mut reexports: BTreeMap<(Vec<String>, String), Vec<String>> = BTreeMap::new();
    for f in files {
        for (public, p) in use_paths(&f.tokens).0 {
            if let (true, Some(name), Some(abs)) =
                (public, &p.name, absolute(f, &p.segments, &by_module))
            {
                reexports.insert((f.module.clone(), name.clone()), abs);
            }
        }
    }
    let resolve = |path: &[String]| -> Option<&SourceFile> {
        let mut path = path.to_vec();
        // Follow re-exports (a few hops at most).
        for _ in 0..8 {
            let k = (0..=path.len())
                .rev()
                .find(|&k| by_module.contains_key(&path[..k]))?;
            let file = by_module[&path[..k]];
            match path.get(k) {
                Some(name) if reexports.contains_key(&(path[..k].to_vec(), name.clone())) => {
                    let mut next = reexports[&(path[..k].to_vec(), name.clone())].clone();
                    next.extend_from_slice(&path[k + 1..]);
                    path = next;
                }
                _ => return Some(file),
            }
        }
        None
    };
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let mut targets = Vec::new();
        let (uses, in_use) = use_paths(&f.tokens);
        for (public, p) in uses {
            // A crate root's `pub use` lines are its façade.
            if public && f.module.is_empty() {
                continue;
            }
            if let Some(abs) = absolute(f, &p.segments, &by_module) {
                targets.push(abs);
            }
        }
        // Paths in code: `crate::a::f`, `super::x`, `self::x`, `child::x`.
        let t = &f.tokens;
        for i in 0..t.len() {
            let Some(first) = ident(t.get(i)) else {
                continue;
            };
            if in_use[i] || (i > 0 && t[i - 1] == Token::Path) {
                continue;
            }
            if t.get(i + 1) != Some(&Token::Path) {
                continue;
            }
            let mut segments = vec![first.to_string()];
            let mut j = i + 1;
            while t.get(j) == Some(&Token::Path) {
                match ident(t.get(j + 1)) {
                    Some(s) => segments.push(s.to_string()),
                    None => break,
                }
                j += 2;
            }
            if let Some(abs) = absolute(f, &segments, &by_module) {
                targets.push(abs);
            }
        }
        let deps = edges.entry(f.name.clone()).or_default();
        for target in targets {
            if let Some(to) = resolve(&target)
                && to.name != f.name
            {
                deps.insert(to.name.clone());
            }
        }
    }
    edges
}

/// The absolute module path of `segments` as written in `file`, when it starts in this
/// crate (`crate`, `super`, `self`, or a child module of the file); `None` for other
/// crates and the standard library.
fn absolute(
    file: &SourceFile,
    segments: &[String],
    by_module: &BTreeMap<&[String], &SourceFile>,
) -> Option<Vec<String>> {
    let first = segments.first()?;
    let mut base = file.module.clone();
    let mut rest = segments;
    match first.as_str() {
        "crate" => {
            base.clear();
            rest = &segments[1..];
        }
        "self" => rest = &segments[1..],
        "super" => {
            // A leaf file `a/b.rs` is module a::b: `super` is a. `a/mod.rs` is a: `super` is
            // the root.
            let mut k = 0;
            while segments.get(k).is_some_and(|s| s == "super") {
                base.pop()?;
                k += 1;
            }
            rest = &segments[k..];
        }
        _ => {
            // A child module of this file's module.
            let mut child = base.clone();
            child.push(first.clone());
            if !by_module.contains_key(child.as_slice()) {
                return None;
            }
        }
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

/// Every cycle of the graph, each as a list of files `a → b → ... → a`, found by depth-first
/// search (one per strongly connected set of files).
fn cycles(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    let mut found: Vec<Vec<String>> = Vec::new();
    let mut seen_sets: BTreeSet<BTreeSet<String>> = BTreeSet::new();
    let mut done: BTreeSet<String> = BTreeSet::new();
    fn visit(
        node: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        stack: &mut Vec<String>,
        done: &mut BTreeSet<String>,
        found: &mut Vec<Vec<String>>,
        seen_sets: &mut BTreeSet<BTreeSet<String>>,
    ) {
        stack.push(node.to_string());
        for next in edges.get(node).into_iter().flatten() {
            if let Some(pos) = stack.iter().position(|s| s == next) {
                let mut cycle = stack[pos..].to_vec();
                let set: BTreeSet<String> = cycle.iter().cloned().collect();
                if seen_sets.insert(set) {
                    cycle.push(next.clone());
                    found.push(cycle);
                }
            } else if !done.contains(next) {
                visit(next, edges, stack, done, found, seen_sets);
            }
        }
        stack.pop();
        done.insert(node.to_string());
    }
    for node in edges.keys() {
        if !done.contains(node) {
            visit(
                node,
                edges,
                &mut Vec::new(),
                &mut done,
                &mut found,
                &mut seen_sets,
            );
        }
    }
    found
}

/// The source roots of the workspace's crates: `crates/*/src`, and `crates/cli` (the
/// binary's files, beside its `main.rs`).
fn crate_roots() -> Vec<(String, PathBuf)> {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut roots: Vec<(String, PathBuf)> = std::fs::read_dir(&crates)
        .unwrap_or_else(|e| panic!("{}: {e}", crates.display()))
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let src = e.path().join("src");
            if src.join("lib.rs").is_file() || src.join("main.rs").is_file() {
                Some((name, src))
            } else if e.path().join("main.rs").is_file() {
                Some((name, e.path()))
            } else {
                None
            }
        })
        .collect();
    roots.sort();
    roots
}

/// `crate: a.rs → b.rs → a.rs` for each cycle of the crate at `root`.
fn describe_cycles(name: &str, root: &Path) -> Vec<String> {
    cycles(&file_graph(&read_crate(root)))
        .into_iter()
        .map(|c| format!("{name}: {}", c.join(" → ")))
        .collect()
}

#[test]
fn no_crate_has_an_import_cycle_between_its_files() {
    let roots = crate_roots();
    assert!(
        roots.iter().any(|(n, _)| n == "pipeline") && roots.len() >= 10,
        "found the crates: {roots:?}"
    );
    let found: Vec<String> = roots
        .iter()
        .flat_map(|(name, root)| describe_cycles(name, root))
        .collect();
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
}

#[test]
fn pipeline_command_modules_do_not_use_one_another() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let edges = file_graph(&read_crate(&root));
    let command = |file: &str| PIPELINE_COMMANDS.iter().any(|c| file == format!("{c}.rs"));
    assert!(edges.keys().filter(|f| command(f)).count() == PIPELINE_COMMANDS.len());
    // The graph is not empty: run uses the frame processor, which uses the stage types.
    assert!(edges["run.rs"].contains("processor.rs"), "{edges:?}");
    assert!(edges["processor.rs"].contains("frame.rs"), "{edges:?}");
    let bad: Vec<String> = edges
        .iter()
        .filter(|(from, _)| command(from))
        .flat_map(|(from, to)| {
            to.iter()
                .filter(|t| command(t))
                .map(move |t| format!("{from} uses {t}"))
        })
        .collect();
    assert!(
        bad.is_empty(),
        "command modules use one another (move the shared helper into a non-command \
         module):\n{}",
        bad.join("\n")
    );
}

/// Writes a crate's files (`(relative path, text)`) into a temporary folder; returns it
/// and its source root.
fn planted(files: &[(&str, &str)]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("temp dir");
    let src = dir.path().join("src");
    for (path, text) in files {
        let path = src.join(path);
        std::fs::create_dir_all(path.parent().expect("a folder")).expect("folder");
        std::fs::write(&path, text).expect("write");
    }
    (dir, src)
}

#[test]
fn a_planted_cycle_is_found() {
    let (_dir, src) = planted(&[
        ("lib.rs", "mod a;\nmod b;\nmod c;\npub use a::A;\n"),
        ("a.rs", "use crate::b::{self, B};\npub struct A;\n"),
        ("b.rs", "pub struct B;\npub fn f() { crate::c::g() }\n"),
        ("c.rs", "pub fn g() { let _ = crate::A; }\n"),
    ]);
    let found = describe_cycles("planted", &src);
    assert_eq!(found, ["planted: a.rs → b.rs → c.rs → a.rs"], "{found:?}");
}

#[test]
fn super_child_modules_and_reexports_are_followed() {
    // p.rs uses its child p/c.rs, which uses an item defined in p.rs: a cycle.
    let (_dir, src) = planted(&[
        ("lib.rs", "mod p;\n"),
        ("p.rs", "mod c;\npub struct Thing;\nfn f() { c::g(); }\n"),
        ("p/c.rs", "use super::Thing;\npub fn g() {}\n"),
    ]);
    assert_eq!(
        describe_cycles("x", &src),
        ["x: p.rs → p/c.rs → p.rs"],
        "child module and super"
    );
    // The same through a mod.rs, and a re-export of a sibling: no cycle when the item the
    // child uses is defined elsewhere.
    let (_dir, src) = planted(&[
        ("lib.rs", "mod p;\n"),
        (
            "p/mod.rs",
            "mod c;\nmod d;\npub use d::Thing;\nfn f() { c::g(); }\n",
        ),
        ("p/c.rs", "use super::Thing;\npub fn g() {}\n"),
        ("p/d.rs", "pub struct Thing;\n"),
    ]);
    let edges = file_graph(&read_crate(&src));
    assert_eq!(
        edges["p/c.rs"],
        BTreeSet::from(["p/d.rs".to_string()]),
        "{edges:?}"
    );
    assert!(describe_cycles("x", &src).is_empty());
}

#[test]
fn comments_strings_and_test_code_are_not_imports() {
    let (_dir, src) = planted(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        (
            "a.rs",
            "/// See [`crate::b`].\n// use crate::b::B;\n/* crate::b::f() */\n\
             pub fn a() -> &'static str { let _c = '\"'; r#\"crate::b::f()\"# }\n",
        ),
        (
            "b.rs",
            "use crate::a::a;\npub fn f() -> &'static str { \"crate::a::a\" }\n\
             #[cfg(test)]\nmod tests {\n    use crate::a::a;\n    fn t() { let _ = '}'; }\n}\n",
        ),
    ]);
    let edges = file_graph(&read_crate(&src));
    assert!(edges["a.rs"].is_empty(), "{edges:?}");
    assert_eq!(edges["b.rs"], BTreeSet::from(["a.rs".to_string()]));
    assert!(describe_cycles("x", &src).is_empty());
    // The same b.rs used by a.rs in code: a cycle.
    let (_dir, src) = planted(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        ("a.rs", "pub fn a() { crate::b::f(); }\n"),
        ("b.rs", "use crate::a::a;\npub fn f() { a() }\n"),
    ]);
    assert_eq!(describe_cycles("x", &src), ["x: a.rs → b.rs → a.rs"]);
}
