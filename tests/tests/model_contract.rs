//! One model contract (`docs/models.md`): its table of ids and parameters,
//! the shared table in code (`gonio_shared::MODELS`), the host's catalog, the
//! head's sanity models and the scipy peer (`bench/python/fit_scipy.py`) name
//! the same models with the same parameters in the same order.

use gonio_brdf::ModelId;
use gonio_shared::{SanityKind, SanityModel, MODELS};
use std::path::Path;

fn repo_file(path: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The backticked words of a table cell, split at commas.
fn ticked(cell: &str) -> Vec<String> {
    cell.split(',').map(|w| w.trim().trim_matches('`').to_string()).collect()
}

/// `(id, parameters)` of each row of the table in §2 of `docs/models.md`.
fn documented() -> Vec<(String, Vec<String>)> {
    let text = repo_file("docs/models.md");
    let start = text.find("## 2. Models").expect("§2 in docs/models.md");
    let end = start + text[start..].find("## 3.").expect("§3 after §2");
    text[start..end]
        .lines()
        .filter(|l| l.starts_with("| `"))
        .map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            (ticked(cells[1]).remove(0), ticked(cells[2]))
        })
        .collect()
}

#[test]
fn the_documented_table_is_the_shared_table() {
    let doc = documented();
    let code: Vec<(String, Vec<String>)> = MODELS
        .iter()
        .map(|m| (m.id.to_string(), m.params.iter().map(|p| p.to_string()).collect()))
        .collect();
    assert_eq!(doc, code);
}

#[test]
fn the_host_catalog_follows_the_table() {
    assert_eq!(ModelId::ALL.len(), MODELS.len());
    for (m, spec) in ModelId::ALL.into_iter().zip(MODELS) {
        assert_eq!(m.spec(), spec);
        assert_eq!(
            serde_json::to_string(&m).unwrap(),
            format!("\"{}\"", spec.id),
            "serde name of {m:?}"
        );
        assert_eq!(ModelId::parse(spec.id).unwrap(), m);
        assert_eq!(m.bounds().len(), spec.arity(), "bounds of {}", spec.id);
    }
}

/// The field names of a sanity model in declaration order, from its `Debug`.
fn field_names(m: &SanityModel) -> Vec<String> {
    let text = format!("{m:?}");
    let inner = &text[text.find('{').expect("a struct variant") + 1..text.rfind('}').unwrap()];
    inner
        .split(',')
        .filter_map(|f| f.split(':').next())
        .map(|n| n.trim().to_string())
        .filter(|n| n != "back")
        .collect()
}

#[test]
fn the_sanity_models_follow_the_table() {
    for kind in [
        SanityKind::Lambert,
        SanityKind::RetroPhong,
        SanityKind::AbcRetro { back: false },
        SanityKind::AbcRetro { back: true },
    ] {
        let spec = kind.spec();
        assert!(MODELS.contains(&spec), "{kind:?}");
        assert_eq!(kind.arity(), spec.arity());
        let values: Vec<f32> = (1..=spec.arity()).map(|k| k as f32).collect();
        let m = SanityModel::from_params(kind, &values).expect("the table's arity");
        assert_eq!(m.kind(), kind);
        assert_eq!(field_names(&m), spec.params, "{kind:?}: fields in the table's order");
        assert_eq!(&m.params()[..], &values[..], "{kind:?}: params() in the table's order");
        assert!(SanityModel::from_params(kind, &[values.clone(), vec![0.0]].concat()).is_none());
    }
}

#[test]
fn the_scipy_peer_unpacks_the_table() {
    let text = repo_file("bench/python/fit_scipy.py");
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let mut seen = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let Some(id) = line.strip_prefix("if name == \"").and_then(|r| r.strip_suffix("\":")) else {
            continue;
        };
        let spec = MODELS
            .iter()
            .find(|m| m.id == id)
            .unwrap_or_else(|| panic!("fit_scipy.py models `{id}`, which the table has not"));
        let unpack = lines[k + 1]
            .strip_suffix(" = p")
            .unwrap_or_else(|| panic!("`{id}`: the line after its test unpacks p, got `{}`", lines[k + 1]));
        let names: Vec<&str> = unpack
            .trim_matches(|c| c == '(' || c == ')')
            .split(',')
            .map(str::trim)
            .filter(|n| !n.is_empty())
            .collect();
        assert_eq!(names, spec.params, "fit_scipy.py `{id}`");
        seen.push(id);
    }
    let all: Vec<&str> = MODELS.iter().map(|m| m.id).collect();
    assert_eq!(seen, all, "fit_scipy.py models every model of the table, in its order");
}
