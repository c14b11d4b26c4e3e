//! The book (`book/src`) and the README hold together: every link leads to a file and a heading
//! that exist, every section the code cites exists, every chapter is in the book's summary, and
//! the tables the code generates are the ones the book shows (`HASEL_BLESS=1` rewrites them).

mod common;

use common::generated_section;
use hasel_fmu::fmu::pack;
use hasel_fmu::model::params::Params;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn book() -> PathBuf {
    root().join("book/src")
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The Markdown files of the book, by file name.
fn chapters() -> BTreeMap<String, PathBuf> {
    std::fs::read_dir(book())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .map(|p| (p.file_name().unwrap().to_string_lossy().to_string(), p))
        .collect()
}

/// The lines of `md` outside fenced code blocks.
fn prose(md: &str) -> Vec<&str> {
    let mut fenced = false;
    md.lines()
        .filter(|l| {
            if l.trim_start().starts_with("```") {
                fenced = !fenced;
                return false;
            }
            !fenced
        })
        .collect()
}

/// The headings' texts, `#` marks and surrounding space taken off.
fn headings(md: &str) -> Vec<String> {
    prose(md)
        .into_iter()
        .filter(|l| l.starts_with('#'))
        .map(|l| l.trim_start_matches('#').trim().to_string())
        .collect()
}

/// The anchor mdBook gives a heading: lower case, spaces to `-`, other punctuation dropped.
fn anchor(heading: &str) -> String {
    heading
        .chars()
        .filter_map(|c| {
            if c.is_alphanumeric() || c == '_' || c == '-' {
                Some(c.to_lowercase().next().unwrap())
            } else if c.is_whitespace() {
                Some('-')
            } else {
                None
            }
        })
        .collect()
}

/// The targets of the inline links and images of `md` (`[text](target)`), code left out.
fn links(md: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in prose(md) {
        // inline code is not a link
        let text: String = line.split('`').step_by(2).collect::<Vec<_>>().join("");
        let mut rest = text.as_str();
        while let Some(at) = rest.find("](") {
            rest = &rest[at + 2..];
            if let Some(end) = rest.find(')') {
                out.push(
                    rest[..end]
                        .split_whitespace()
                        .next()
                        .unwrap_or("")
                        .to_string(),
                );
                rest = &rest[end..];
            }
        }
    }
    out
}

/// What is wrong with the link `target` of the file `from`, if anything.
fn broken(from: &Path, target: &str) -> Option<String> {
    if target.starts_with("http://") || target.starts_with("https://") || target.is_empty() {
        return None;
    }
    let (file, fragment) = target.split_once('#').unwrap_or((target, ""));
    let path = if file.is_empty() {
        from.to_path_buf()
    } else {
        from.parent().unwrap().join(file)
    };
    let Ok(path) = path.canonicalize() else {
        return Some(format!("{target}: no such file"));
    };
    let in_book = from.starts_with(book());
    if in_book && !path.starts_with(book().canonicalize().unwrap()) {
        return Some(format!(
            "{target}: outside book/src, which the built book cannot serve (name the file in code)"
        ));
    }
    if !fragment.is_empty() && path.extension().is_some_and(|x| x == "md") {
        let known: BTreeSet<String> = headings(&read(&path)).iter().map(|h| anchor(h)).collect();
        if !known.contains(fragment) {
            return Some(format!("{target}: no heading with the anchor #{fragment}"));
        }
    }
    None
}

#[test]
fn every_link_of_the_book_and_the_readme_leads_somewhere() {
    let mut files: Vec<PathBuf> = chapters().into_values().collect();
    files.push(root().join("README.md"));
    let mut wrong = Vec::new();
    for file in &files {
        for target in links(&read(file)) {
            if let Some(why) = broken(file, &target) {
                wrong.push(format!("{}: {why}", file.display()));
            }
        }
    }
    assert!(wrong.is_empty(), "broken links:\n{}", wrong.join("\n"));
}

#[test]
fn every_chapter_is_in_the_summary() {
    let summary = read(&book().join("SUMMARY.md"));
    let listed: BTreeSet<String> = links(&summary).into_iter().collect();
    let missing: Vec<String> = chapters()
        .into_keys()
        .filter(|name| name != "SUMMARY.md" && !listed.contains(name))
        .collect();
    assert!(
        missing.is_empty(),
        "chapters not in SUMMARY.md: {missing:?}"
    );
}

/// The text of a source file with its lines joined and comment marks taken off, so that a
/// citation wrapped over two comment lines reads as one.
fn joined(text: &str) -> String {
    text.lines()
        .map(|l| {
            let l = l.trim_start();
            ["//!", "///", "//", "#"]
                .iter()
                .find_map(|m| l.strip_prefix(m))
                .unwrap_or(l)
                .trim()
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Every citation `NAME.md, "Section"` or `README, "Section"` in `text` (the link form
/// `[NAME.md](…), "Section"` included), as the cited file name and the section.
fn citations(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (at, _) in text
        .match_indices(".md")
        .chain(text.match_indices("README"))
    {
        let end = if text[at..].starts_with(".md") {
            at + 3
        } else {
            at + 6
        };
        let start = text[..at]
            .rfind(|c: char| !(c.is_alphanumeric() || "_-/".contains(c)))
            .map_or(0, |i| i + 1);
        let name = format!("{}{}", &text[start..at], &text[at..end]);
        let rest = &text[end..];
        // a link's text (its target is read next) or a path in a string (`"effects.md")`)
        if rest.starts_with("](") || rest.starts_with('"') {
            continue;
        }
        let rest = rest.strip_prefix(')').unwrap_or(rest);
        let rest = rest.strip_prefix(',').unwrap_or(rest).trim_start();
        if let Some(quoted) = rest.strip_prefix('"')
            && let Some((section, _)) = quoted.split_once('"')
        {
            out.push((
                name,
                section.split_whitespace().collect::<Vec<_>>().join(" "),
            ));
        }
    }
    out
}

/// Every file of the repository's code and documents that may cite a section.
fn citing_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            if path.is_dir() {
                if !["target", "corpus", "artifacts", "html", "__pycache__"]
                    .contains(&name.as_str())
                {
                    walk(&path, out);
                }
            } else if ["rs", "py", "sh", "md", "toml", "c"]
                .iter()
                .any(|x| path.extension().is_some_and(|e| e == *x))
            {
                out.push(path);
            }
        }
    }
    let mut out = vec![root().join("README.md"), root().join("Cargo.toml")];
    for dir in ["src", "tests", "ci", "examples", "python", "book/src"] {
        walk(&root().join(dir), &mut out);
    }
    out
}

/// What a citation may name in a document: its headings and the run-in titles that open a
/// paragraph (`**Jacobian.** Every term …`).
fn sections(path: &Path) -> BTreeSet<String> {
    let md = read(path);
    let run_in = prose(&md).into_iter().filter_map(|l| {
        let title = l.strip_prefix("**")?.split_once("**")?.0;
        Some(title.trim_end_matches(['.', ':']).to_string())
    });
    headings(&md).into_iter().chain(run_in).collect()
}

#[test]
fn every_cited_section_exists() {
    let chapters = chapters();
    let mut known: BTreeMap<String, BTreeSet<String>> = chapters
        .iter()
        .map(|(name, path)| (name.clone(), sections(path)))
        .collect();
    known.insert("README".into(), sections(&root().join("README.md")));
    let mut wrong = Vec::new();
    let mut count = 0;
    for file in citing_files() {
        // this file's own examples are not citations
        if file.ends_with("tests/docs.rs") {
            continue;
        }
        for (name, section) in citations(&joined(&read(&file))) {
            let chapter = name.rsplit('/').next().unwrap().trim_end_matches(".md");
            let key = if chapter == "README" {
                "README".to_string()
            } else {
                format!("{chapter}.md")
            };
            let Some(headings) = known.get(&key) else {
                continue; // a file the program writes (report.md), not a document
            };
            count += 1;
            if !headings.contains(&section) {
                wrong.push(format!("{}: {name}, \"{section}\"", file.display()));
            }
        }
    }
    assert!(
        count > 100,
        "only {count} citations found: the reader of them is broken"
    );
    assert!(
        wrong.is_empty(),
        "cited sections that do not exist:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_reader_of_citations_finds_each_form() {
    let text = joined(
        "// as (book/src/model.md,\n// \"Shell geometry and C2\"), [identify.md](identify.md), \"Fit metric\"\n\
         /// README, \"The FMU\"; report.md with its figures",
    );
    assert_eq!(
        citations(&text),
        [
            ("book/src/model.md".into(), "Shell geometry and C2".into()),
            ("identify.md".into(), "Fit metric".into()),
            ("README".into(), "The FMU".into()),
        ]
    );
    assert_eq!(
        anchor("What `hasel diagnose` answers"),
        "what-hasel-diagnose-answers"
    );
}

#[test]
fn the_book_shows_the_fmus_variables_as_the_fmus_document_them() {
    let params = Params::default();
    generated_section(
        &book().join("parameters.md"),
        "platform variables",
        &pack::variables_markdown(&pack::platform(&params)),
    );
    generated_section(
        &book().join("parameters.md"),
        "inverse variables",
        &pack::variables_markdown(&pack::inverse(&params)),
    );
}
