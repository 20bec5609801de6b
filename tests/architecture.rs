//! The house rules of the tree, checked on the source (see docs/ARCHITECTURE.md): the pipeline's
//! stages import only what lies before them, geometry decisions go through one module, `unsafe`
//! lives in one file, the library does not use `anyhow`, and files stay small.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

fn src() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The library's source files (the binary's `cli/` and `main.rs` left out), with their top-level
/// module and their code: comments and the unit-test module at the end of a file removed.
fn library() -> Vec<(PathBuf, String, String)> {
    let root = src();
    let mut all = Vec::new();
    files(&root, &mut all);
    all.sort();
    all.into_iter()
        .filter_map(|p| {
            let rel = p.strip_prefix(&root).unwrap().to_path_buf();
            let first = rel.components().next()?.as_os_str().to_str()?.to_string();
            if first == "cli" || first == "main.rs" || rel.ends_with("tests.rs") {
                return None;
            }
            let top = first.trim_end_matches(".rs").to_string();
            let text = std::fs::read_to_string(&p).unwrap();
            let code = match text.find("#[cfg(test)]\nmod tests") {
                Some(i) => &text[..i],
                None => &text[..],
            };
            let code: String = code
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect::<Vec<_>>()
                .join("\n");
            Some((rel, top, code))
        })
        .collect()
}

/// Which top-level modules each top-level module names as `crate::module`.
fn imports() -> BTreeMap<String, BTreeSet<String>> {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (_, top, code) in library() {
        let mut rest = code.as_str();
        while let Some(i) = rest.find("crate::") {
            rest = &rest[i + 7..];
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_lowercase() || *c == '_')
                .collect();
            if !name.is_empty() && name != top {
                g.entry(top.clone()).or_default().insert(name);
            }
        }
    }
    g
}

#[test]
fn stages_import_only_what_comes_before_them() {
    let g = imports();
    let never = |module: &str, forbidden: &[&str]| {
        let deps = g.get(module).cloned().unwrap_or_default();
        for f in forbidden {
            assert!(
                !deps.contains(*f),
                "`{module}` must not import `{f}` (it imports {deps:?})"
            );
        }
    };
    let late = [
        "input", "output", "products", "pipeline", "tiles", "plan", "sink",
    ];
    // Geometry first: the predicates and exact helpers need nothing but the error type.
    let geom: Vec<&String> = g
        .get("geom")
        .map(|d| d.iter().filter(|m| *m != "error").collect())
        .unwrap_or_default();
    assert!(geom.is_empty(), "`geom` imports {geom:?}");
    // The core knows nothing of files, products or how runs are organised.
    for core in [
        "mesh",
        "sweep",
        "finalise",
        "sort",
        "tin",
        "triangulation",
        "validate",
    ] {
        never(core, &late);
    }
    // Readers come before the sweep and the outputs.
    never(
        "input",
        &[
            "sweep", "finalise", "output", "products", "pipeline", "tiles", "plan", "sink",
        ],
    );
    // Products and writers consume triangles; they do not run triangulations.
    for consumer in ["products", "output"] {
        never(
            consumer,
            &["pipeline", "tiles", "plan", "sweep", "finalise"],
        );
    }
    never(
        "sink",
        &["pipeline", "tiles", "plan", "sweep", "products", "input"],
    );
    // Plans are built on tiles, never the other way round.
    for m in g.keys().filter(|m| *m != "plan" && *m != "lib") {
        never(m, &["plan"]);
    }
}

#[test]
fn the_import_graph_has_no_circles() {
    let g = imports();
    // Depth-first search; a module met again while on the path closes a circle.
    fn visit(
        m: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) {
        if done.contains(m) {
            return;
        }
        if let Some(i) = path.iter().position(|p| p == m) {
            panic!("import circle: {} -> {m}", path[i..].join(" -> "));
        }
        path.push(m.to_string());
        for d in g.get(m).into_iter().flatten() {
            visit(d, g, path, done);
        }
        path.pop();
        done.insert(m.to_string());
    }
    let mut done = BTreeSet::new();
    for m in g.keys() {
        visit(m, &g, &mut Vec::new(), &mut done);
    }
}

#[test]
fn one_home_for_predicates_unsafe_and_anyhow() {
    for (rel, _, code) in library() {
        let name = rel.to_string_lossy().replace('\\', "/");
        if code.contains("robust::") {
            assert_eq!(name, "geom/predicates.rs", "{name} calls `robust` directly");
        }
        if code.contains("unsafe ") || code.contains("allow(unsafe_code)") {
            assert_eq!(name, "sort/mmap.rs", "{name} has unsafe code");
        }
        assert!(
            !code.contains("anyhow"),
            "{name}: the library uses `anyhow`"
        );
        assert!(
            !code.contains(".expect(\"streaming\")"),
            "{name}: the streaming sweep owns its finaliser"
        );
    }
}

#[test]
fn files_stay_small() {
    let mut all = Vec::new();
    files(&src(), &mut all);
    for p in all {
        let n = std::fs::read_to_string(&p).unwrap().lines().count();
        assert!(
            n <= 800,
            "{} has {n} lines (keep files under ~800)",
            p.display()
        );
    }
}

#[test]
fn the_engine_is_not_public_api() {
    // The engine is `pub(crate)` in a normal build; the `dev` feature (the crate's own tests,
    // benchmarks and `dev/` tools) makes it `pub` through lib.rs's `internal!` macro.
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    let lines: Vec<&str> = lib.lines().map(str::trim).collect();
    let block = lines
        .iter()
        .position(|l| *l == "internal! {")
        .expect("lib.rs declares the engine's modules with `internal! { … }`");
    let end = block + lines[block..].iter().position(|l| *l == "}").unwrap();
    let internal = &lines[block + 1..end];
    for name in ["finalise", "geom", "mesh", "sort", "sweep", "tiles", "tin"] {
        assert!(
            internal.contains(&format!("mod {name};").as_str()),
            "lib.rs: `{name}` is not declared in `internal!`"
        );
    }
    for name in ["clock", "idmap"] {
        assert!(
            lines.contains(&format!("pub(crate) mod {name};").as_str()),
            "lib.rs: `{name}` is not `pub(crate)`"
        );
    }
    for (i, l) in lines.iter().enumerate() {
        let Some(name) = l.strip_prefix("pub mod ").and_then(|n| n.strip_suffix(';')) else {
            continue;
        };
        let internal = [
            "clock", "finalise", "geom", "idmap", "mesh", "sort", "sweep", "tiles", "tin",
        ];
        assert!(
            !internal.contains(&name),
            "lib.rs declares the internal module `{name}` as `pub mod`"
        );
        if name == "synth" {
            assert!(
                lines[i.saturating_sub(2)..i].contains(&"#[cfg(any(test, feature = \"dev\"))]"),
                "lib.rs: `synth` is only for tests and `dev` builds"
            );
        }
    }
}

/// The integration tests are one binary (`tests/all.rs`, `autotests = false`): a test file it
/// does not declare would never run, and pass.
#[test]
fn every_test_file_is_a_module_of_the_one_test_binary() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests");
    let all = std::fs::read_to_string(dir.join("all.rs")).unwrap();
    // The test files' modules: those without a `#[path]` (the helpers in tests/support have one).
    let lines: Vec<&str> = all.lines().collect();
    let declared: BTreeSet<&str> = lines
        .iter()
        .enumerate()
        .filter(|&(i, _)| i == 0 || !lines[i - 1].starts_with("#[path"))
        .filter_map(|(_, l)| l.strip_prefix("mod ")?.strip_suffix(';'))
        .collect();
    let mut files = BTreeSet::new();
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        let Some(stem) = p.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        if p.extension().is_some_and(|e| e == "rs") && stem != "all" {
            files.insert(stem.to_string());
        }
    }
    let files: BTreeSet<&str> = files.iter().map(String::as_str).collect();
    assert_eq!(
        files, declared,
        "tests/all.rs must declare `mod NAME;` for every tests/NAME.rs (and nothing else)"
    );
}
