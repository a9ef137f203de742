//! The HTTP API's reference, `API.md`, against the routes the server
//! registers: every route has a heading `### METHOD /path` and every such
//! heading is a route; the studio serves the file at `GET /api`, and each
//! documented route answers (nothing falls through to the 404 handler).

use microfrep_studio::{ServeOptions, Studio, API_MD, ROUTES};
use std::collections::BTreeSet;
use std::time::Duration;

/// `(METHOD, path)` of every `### METHOD /path` heading.
fn documented(md: &str) -> Vec<(String, String)> {
    md.lines()
        .filter_map(|l| l.strip_prefix("### "))
        .filter_map(|h| {
            let (m, p) = h.trim().split_once(' ')?;
            (["GET", "POST"].contains(&m) && p.starts_with('/') && !p.contains(' '))
                .then(|| (m.to_string(), p.to_string()))
        })
        .collect()
}

#[test]
fn every_route_is_documented_and_every_documented_route_exists() {
    let file = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/API.md")).unwrap();
    assert_eq!(file, API_MD, "the served API.md is the crate's file");
    let docs = documented(&file);
    let doc_set: BTreeSet<_> = docs.iter().cloned().collect();
    assert_eq!(doc_set.len(), docs.len(), "a route is documented twice");
    let routes: Vec<(String, String)> = ROUTES
        .iter()
        .map(|r| (r.method.to_string(), r.path.to_string()))
        .collect();
    let route_set: BTreeSet<_> = routes.iter().cloned().collect();
    assert_eq!(route_set.len(), routes.len(), "a route is registered twice");
    let missing: Vec<_> = route_set.difference(&doc_set).collect();
    assert!(
        missing.is_empty(),
        "routes without a '### METHOD /path' section in API.md: {missing:?}"
    );
    let stale: Vec<_> = doc_set.difference(&route_set).collect();
    assert!(
        stale.is_empty(),
        "API.md documents routes the server does not have: {stale:?}"
    );
    // The extraction sees the whole table (a guard against a parser that
    // finds nothing and so agrees with anything).
    assert!(routes.len() >= 20, "{routes:?}");
    for want in [
        "/api",
        "/api/edit",
        "/api/state",
        "/api/mesh",
        "/api/slices",
    ] {
        assert!(routes.iter().any(|r| r.1 == want), "{want}");
    }
}

#[test]
fn api_is_served_and_every_route_is_answered() {
    let dir = std::env::temp_dir().join(format!("mf-studio-api-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let studio = Studio::start(ServeOptions {
        port: 0,
        root: dir.clone(),
        levels: vec![16],
        analysis: [16, 16],
        settle: Duration::ZERO,
        ..ServeOptions::default()
    })
    .unwrap();
    let c = studio.client();
    let r = c.get("/api").unwrap();
    assert_eq!(r.status, 200);
    assert_eq!(
        r.header("content-type"),
        Some("text/markdown; charset=utf-8")
    );
    assert_eq!(String::from_utf8(r.body).unwrap(), API_MD);
    // Every registered route reaches its handler: whatever it answers to a
    // bare request (400 for missing parameters), it is not the unknown
    // endpoint's 404.
    for route in ROUTES {
        let body = (route.method == "POST").then_some(&b"{}"[..]);
        let r = c.request(route.method, route.path, body, &[]).unwrap();
        let text = String::from_utf8_lossy(&r.body);
        assert!(
            !(r.status == 404 && text.contains("no such endpoint")),
            "{route:?} is registered but not answered: {text}"
        );
    }
    let r = c.get("/api/nothing").unwrap();
    assert_eq!(r.status, 404);
    assert!(String::from_utf8_lossy(&r.body).contains("no such endpoint: GET /api/nothing"));
    studio.stop();
    let _ = std::fs::remove_dir_all(&dir);
}
