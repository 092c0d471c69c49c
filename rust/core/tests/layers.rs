//! The core's modules stack without cycles: no module reaches, through `crate::` paths in
//! its non-test code, a module that reaches it back. Scenario is at the bottom: it knows
//! nothing of the grid, the generator, the planner or name resolution.

use std::collections::{BTreeMap, BTreeSet};

fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut code = BTreeMap::new();
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        // A module is a file `src/m.rs` or a folder `src/m/` (its files together).
        let files: Vec<std::path::PathBuf> = if path.is_dir() {
            std::fs::read_dir(&path)
                .unwrap()
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "rs"))
                .collect()
        } else if path.extension().is_some_and(|e| e == "rs") && name != "lib" {
            vec![path.clone()]
        } else {
            vec![]
        };
        if !files.is_empty() {
            // Non-test code of each file (up to its first `#[cfg(test)]`), comments left
            // out below.
            let text: String = files
                .iter()
                .filter(|p| !p.ends_with("tests.rs"))
                .map(|p| {
                    let t = std::fs::read_to_string(p).unwrap();
                    t.split("#[cfg(test)]").next().unwrap().to_string()
                })
                .collect::<Vec<_>>()
                .join("\n");
            let lines: Vec<&str> = text
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect();
            code.insert(name, lines.join("\n"));
        }
    }
    let names: BTreeSet<String> = code.keys().cloned().collect();
    code.iter()
        .map(|(m, text)| {
            let deps = text
                .split("crate::")
                .skip(1)
                .map(|rest| {
                    rest.chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect::<String>()
                })
                .filter(|d| d != m && names.contains(d))
                .collect();
            (m.clone(), deps)
        })
        .collect()
}

fn reaches(g: &BTreeMap<String, BTreeSet<String>>, from: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut todo = vec![from.to_string()];
    while let Some(m) = todo.pop() {
        for d in &g[&m] {
            if seen.insert(d.clone()) {
                todo.push(d.clone());
            }
        }
    }
    seen
}

#[test]
fn no_module_reaches_itself() {
    let g = graph();
    assert!(g.len() >= 10, "{g:?}");
    for m in g.keys() {
        assert!(!reaches(&g, m).contains(m), "{m} is on a cycle: {g:?}");
    }
}

#[test]
fn scenario_is_at_the_bottom() {
    let g = graph();
    let below = reaches(&g, "scenario");
    for upper in [
        "grid",
        "generator",
        "planner",
        "clearance",
        "names",
        "replanning",
    ] {
        assert!(
            !below.contains(upper),
            "scenario reaches {upper}: {below:?}"
        );
    }
    assert!(reaches(&g, "names").contains("generator"));
}
