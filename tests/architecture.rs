//! The house keeps its arrows one-way: each room of `src/` may use only the rooms below it
//! (book/src/architecture.md, "The house"), and no two files import each other round a circle. Read from the
//! code's own `crate::` and `super::` paths (comments left out), so a new import that runs back up
//! fails here as it would in a workspace of crates.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Each room of the library and the rooms it may use. The ground floor (model, solver, the
/// FMI layers) knows nothing of the others; the FMI shells share only `fmi_common`.
const ROOMS: &[(&str, &[&str])] = &[
    ("model", &[]),
    ("solver", &[]),
    ("fmi_common", &[]),
    ("fmi2", &["fmi_common"]),
    ("fmi3", &["fmi_common"]),
    ("simulation", &["model", "solver"]),
    ("io", &["model", "simulation"]),
    ("plot", &["io"]),
    (
        "fmu",
        &["fmi_common", "fmi2", "fmi3", "io", "model", "simulation"],
    ),
    ("identify", &["io", "model", "plot", "simulation"]),
    (
        "diagnose",
        &["identify", "io", "model", "plot", "simulation"],
    ),
    ("control", &["io", "model", "plot", "simulation", "solver"]),
    (
        "uncertainty",
        &["identify", "io", "model", "plot", "simulation"],
    ),
];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every `.rs` file under `dir`, test modules (`tests.rs`, `tests/`) left out.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        if stem == "tests" {
            continue;
        }
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|x| x == "rs") {
            out.push(path);
        }
    }
}

/// Every path written after `root::` in `text`, groups expanded:
/// `crate::{a::{b, c}, d}` gives [a, b], [a, c], [d].
fn paths_after(text: &str, root: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let pattern = format!("{root}::");
    let mut from = 0;
    while let Some(at) = text[from..].find(&pattern) {
        let start = from + at;
        from = start + pattern.len();
        let before = text[..start].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // part of a longer name
        }
        let mut tokens = tokenize(&text[from..]);
        parse_tree(&mut tokens, Vec::new(), &mut out);
    }
    out
}

#[derive(Debug, PartialEq)]
enum Token {
    Name(String),
    Sep,
    Open,
    Close,
    Comma,
}

/// The tokens of one path tree, up to where it ends.
fn tokenize(text: &str) -> std::vec::IntoIter<Token> {
    let mut tokens = Vec::new();
    let mut depth = 0usize;
    let mut chars = text.chars().peekable();
    while let Some(&c) = chars.peek() {
        if c.is_alphanumeric() || c == '_' || c == '*' {
            let mut name = String::new();
            while let Some(&c) = chars.peek() {
                if c.is_alphanumeric() || c == '_' || c == '*' {
                    name.push(c);
                    chars.next();
                } else {
                    break;
                }
            }
            tokens.push(Token::Name(name));
        } else if c == ':' {
            chars.next();
            if chars.next_if_eq(&':').is_none() {
                break;
            }
            tokens.push(Token::Sep);
        } else if c == '{' {
            depth += 1;
            chars.next();
            tokens.push(Token::Open);
        } else if c == '}' && depth > 0 {
            depth -= 1;
            chars.next();
            tokens.push(Token::Close);
            if depth == 0 {
                break;
            }
        } else if c == ',' && depth > 0 {
            chars.next();
            tokens.push(Token::Comma);
        } else if c.is_whitespace() && depth > 0 {
            chars.next();
        } else {
            break;
        }
    }
    tokens.into_iter()
}

fn parse_tree(
    tokens: &mut std::vec::IntoIter<Token>,
    prefix: Vec<String>,
    out: &mut Vec<Vec<String>>,
) {
    let mut path = prefix;
    loop {
        match tokens.next() {
            Some(Token::Name(n)) if n == "as" => {
                tokens.next(); // the alias
                out.push(path);
                return;
            }
            Some(Token::Name(n)) => path.push(n),
            Some(Token::Sep) => {}
            Some(Token::Open) => {
                loop {
                    parse_tree(tokens, path.clone(), out);
                    // parse_tree stops after a comma or at the group's close
                    if !matches!(tokens.as_slice().first(), Some(Token::Comma)) {
                        break;
                    }
                    tokens.next();
                }
                if matches!(tokens.as_slice().first(), Some(Token::Close)) {
                    tokens.next();
                }
                return;
            }
            Some(Token::Comma) | Some(Token::Close) | None => {
                if !path.is_empty() {
                    out.push(path);
                }
                return;
            }
        }
        if matches!(
            tokens.as_slice().first(),
            Some(Token::Comma) | Some(Token::Close)
        ) {
            if !path.is_empty() {
                out.push(path);
            }
            return;
        }
    }
}

/// The file a module path leads to, walking from the crate root's folder as far as files go.
fn resolve(root: &Path, base: &[String], path: &[String]) -> Option<PathBuf> {
    let mut dir = root.to_path_buf();
    let mut file = None;
    for seg in base.iter().chain(path) {
        if dir.join(format!("{seg}.rs")).is_file() {
            file = Some(dir.join(format!("{seg}.rs")));
            dir = dir.join(seg);
        } else if dir.join(seg).join("mod.rs").is_file() {
            file = Some(dir.join(seg).join("mod.rs"));
            dir = dir.join(seg);
        } else {
            break;
        }
    }
    file
}

/// A file's module path below its crate root (`src/fmi2/instance.rs` -> [fmi2, instance]).
fn module_of(root: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(root).unwrap();
    let mut segs: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if matches!(
        segs.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        segs.pop();
    }
    segs
}

/// Arrows between the files of one crate root: file -> files it names.
fn arrows(root: &Path, files: &[PathBuf]) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let mut graph = BTreeMap::new();
    for file in files {
        // code only: a doc link names a type without depending on it
        let text: String = std::fs::read_to_string(file)
            .unwrap()
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        let module = module_of(root, file);
        let mut to = BTreeSet::new();
        for path in paths_after(&text, "crate") {
            to.extend(resolve(root, &[], &path));
        }
        let parent = &module[..module.len().saturating_sub(1)];
        for path in paths_after(&text, "super") {
            to.extend(resolve(root, parent, &path));
        }
        to.remove(file);
        graph.insert(file.clone(), to);
    }
    graph
}

/// The room of a library file: its first folder or file below `src/`.
fn room(file: &Path) -> String {
    module_of(&src(), file).first().cloned().unwrap_or_default()
}

#[test]
fn each_room_uses_only_the_rooms_below_it() {
    let mut files = Vec::new();
    sources(&src(), &mut files);
    files.retain(|f| !f.starts_with(src().join("bin")));
    let allowed: BTreeMap<&str, &[&str]> = ROOMS.iter().copied().collect();
    let mut wrong = Vec::new();
    for (from, to) in arrows(&src(), &files) {
        let from_room = room(&from);
        if from_room.is_empty() {
            continue; // lib.rs declares the rooms
        }
        let Some(may) = allowed.get(from_room.as_str()) else {
            wrong.push(format!(
                "{}: room '{from_room}' is not in the table",
                from.display()
            ));
            continue;
        };
        for target in to {
            let target_room = room(&target);
            if target_room != from_room && !may.contains(&target_room.as_str()) {
                wrong.push(format!(
                    "{} uses {} ({from_room} -> {target_room})",
                    from.display(),
                    target.display()
                ));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "arrows against the layers:\n{}",
        wrong.join("\n")
    );
}

/// Strongly connected sets of more than one file, where a folder's `mod.rs` (which declares its
/// files and may re-export them) is left out.
fn circles(graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> Vec<Vec<PathBuf>> {
    let is_mod = |f: &PathBuf| {
        f.file_name()
            .is_some_and(|n| n == "mod.rs" || n == "main.rs")
    };
    let nodes: Vec<&PathBuf> = graph.keys().filter(|f| !is_mod(f)).collect();
    let reach = |from: &PathBuf| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(f) = stack.pop() {
            for t in graph.get(&f).into_iter().flatten() {
                if !is_mod(t) && seen.insert(t.clone()) {
                    stack.push(t.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&PathBuf, BTreeSet<PathBuf>> =
        nodes.iter().map(|f| (*f, reach(f))).collect();
    let mut out: Vec<Vec<PathBuf>> = Vec::new();
    for f in &nodes {
        let circle: Vec<PathBuf> = nodes
            .iter()
            .filter(|g| reached[*f].contains(**g) && reached[**g].contains(*f))
            .map(|g| (*g).clone())
            .collect();
        if circle.len() > 1 && !out.contains(&circle) {
            out.push(circle);
        }
    }
    out
}

#[test]
fn no_files_import_each_other_round_a_circle() {
    let mut lib = Vec::new();
    sources(&src(), &mut lib);
    let (bin, lib): (Vec<_>, Vec<_>) = lib
        .into_iter()
        .partition(|f| f.starts_with(src().join("bin")));
    let bin_root = src().join("bin/hasel");
    let mut found = circles(&arrows(&src(), &lib));
    found.extend(circles(&arrows(&bin_root, &bin)));
    let shown: Vec<String> = found
        .iter()
        .map(|c| {
            c.iter()
                .map(|f| f.display().to_string())
                .collect::<Vec<_>>()
                .join(" <-> ")
        })
        .collect();
    assert!(
        shown.is_empty(),
        "files in a circle of imports:\n{}",
        shown.join("\n")
    );
}

#[test]
fn the_reader_of_paths_finds_grouped_and_nested_imports() {
    let text =
        "use crate::{io::csv::{Table, FileError}, model as m};\nlet x = crate::plot::draw();";
    let paths = paths_after(text, "crate");
    let joined: Vec<String> = paths.iter().map(|p| p.join("::")).collect();
    assert_eq!(
        joined,
        [
            "io::csv::Table",
            "io::csv::FileError",
            "model",
            "plot::draw"
        ]
    );
    assert!(paths_after("my_crate::x", "crate").is_empty());
}

#[test]
fn a_circle_of_two_files_is_seen() {
    let a = PathBuf::from("src/x/a.rs");
    let b = PathBuf::from("src/x/b.rs");
    let graph = BTreeMap::from([
        (a.clone(), BTreeSet::from([b.clone()])),
        (b.clone(), BTreeSet::from([a.clone()])),
    ]);
    assert_eq!(circles(&graph), vec![vec![a, b]]);
}

/// The rooms each room uses, as the imports of its files have them: the library's rooms by their
/// `crate::` and `super::` paths, the command `hasel` (`src/bin/hasel`) by its `hasel_fmu::` ones.
fn house() -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    sources(&src(), &mut files);
    let (bin, lib): (Vec<_>, Vec<_>) = files
        .into_iter()
        .partition(|f| f.starts_with(src().join("bin")));
    let mut uses: BTreeMap<String, BTreeSet<String>> = ROOMS
        .iter()
        .map(|(r, _)| (r.to_string(), BTreeSet::new()))
        .collect();
    for (from, to) in arrows(&src(), &lib) {
        let from_room = room(&from);
        if from_room.is_empty() {
            continue; // lib.rs declares the rooms
        }
        let used = uses.entry(from_room.clone()).or_default();
        used.extend(to.iter().map(|t| room(t)).filter(|r| *r != from_room));
    }
    let cli = uses.entry(CLI.to_string()).or_default();
    for file in bin {
        let text = std::fs::read_to_string(&file).unwrap();
        cli.extend(
            paths_after(&text, "hasel_fmu")
                .into_iter()
                .filter_map(|p| p.first().cloned())
                .filter(|r| ROOMS.iter().any(|(room, _)| room == r)),
        );
    }
    uses
}

const CLI: &str = "bin/hasel";

/// A room's floor: one above the highest room it uses, 0 for a room that uses none.
fn floor(room: &str, uses: &BTreeMap<String, BTreeSet<String>>) -> usize {
    uses[room]
        .iter()
        .map(|r| floor(r, uses) + 1)
        .max()
        .unwrap_or(0)
}

/// The first sentence of a room's module documentation, its links reduced to their text.
fn purpose(room: &str) -> String {
    let file = [
        src().join(room).join("main.rs"),
        src().join(room).join("mod.rs"),
        src().join(format!("{room}.rs")),
    ]
    .into_iter()
    .find(|f| f.is_file())
    .unwrap_or_else(|| panic!("room {room}: no main.rs, mod.rs or {room}.rs"));
    let text = std::fs::read_to_string(&file).unwrap();
    let doc: Vec<&str> = text
        .lines()
        .map_while(|l| l.strip_prefix("//!"))
        .map(str::trim)
        .take_while(|l| !l.is_empty())
        .collect();
    let doc = doc.join(" ");
    let mut plain = String::new();
    let mut rest = doc.as_str();
    while let Some(at) = rest.find("](") {
        plain.push_str(&rest[..at]);
        rest = rest[at + 2..]
            .split_once(')')
            .map_or("", |(_, after)| after);
    }
    plain.push_str(rest);
    let plain = plain.replace(['[', ']'], "");
    match plain.find(". ") {
        Some(end) => plain[..=end].to_string(),
        None => plain,
    }
}

/// The house drawn from the code: each room's floor, the rooms it uses and what it is for, top
/// floor first; the README and book/src/architecture.md show it.
fn drawing() -> String {
    let uses = house();
    let mut rooms: Vec<(usize, &String)> = uses.keys().map(|r| (floor(r, &uses), r)).collect();
    rooms.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(b.1)));
    let arrows: usize = uses.values().map(BTreeSet::len).sum();
    let mut md = format!(
        "{} rooms on {} floors, {arrows} arrows between rooms, every one pointing down:\n\n\
         | floor | room | uses | what it is |\n|---|---|---|---|\n",
        rooms.len(),
        rooms[0].0 + 1,
    );
    for (floor, room) in rooms {
        let used: Vec<&str> = uses[room].iter().map(String::as_str).collect();
        md.push_str(&format!(
            "| {floor} | `src/{room}` | {} | {} |\n",
            used.join(", "),
            purpose(room)
        ));
    }
    md
}

#[test]
fn the_readme_and_the_book_draw_the_house_as_the_code_has_it() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let drawing = drawing();
    common::generated_section(&root.join("README.md"), "house", &drawing);
    common::generated_section(&root.join("book/src/architecture.md"), "house", &drawing);
}
