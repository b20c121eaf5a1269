//! The page's files, embedded in the binary so `photonix serve` needs nothing else at run time.
//! `web/` holds them; `web/vendor/` is three.js, refreshed from npm by `web/vendor.sh`.

/// (URL path, content type, bytes).
const ASSETS: &[(&str, &str, &[u8])] = &[
    ("/", "text/html; charset=utf-8", include_bytes!("../../web/index.html")),
    ("/index.html", "text/html; charset=utf-8", include_bytes!("../../web/index.html")),
    ("/app.js", "text/javascript; charset=utf-8", include_bytes!("../../web/app.js")),
    ("/viewport.js", "text/javascript; charset=utf-8", include_bytes!("../../web/viewport.js")),
    ("/panels.js", "text/javascript; charset=utf-8", include_bytes!("../../web/panels.js")),
    ("/style.css", "text/css; charset=utf-8", include_bytes!("../../web/style.css")),
    (
        "/vendor/three.module.min.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/vendor/three.module.min.js"),
    ),
    (
        "/vendor/OrbitControls.min.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/vendor/OrbitControls.min.js"),
    ),
    (
        "/vendor/TransformControls.min.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/vendor/TransformControls.min.js"),
    ),
];

/// The content type and bytes of the asset at `path`; `None` for anything else (there is no
/// file system behind these URLs, so no path can reach outside them).
pub fn asset(path: &str) -> Option<(&'static str, &'static [u8])> {
    ASSETS.iter().find(|(p, _, _)| *p == path).map(|(_, mime, bytes)| (*mime, *bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_asset_is_there_and_nothing_else() {
        for (path, _, bytes) in ASSETS {
            assert!(!bytes.is_empty(), "{path} is empty");
        }
        assert!(asset("/vendor/three.module.min.js").is_some());
        for path in ["/../Cargo.toml", "/vendor/../app.js", "/etc/passwd", "/app.js/"] {
            assert!(asset(path).is_none(), "{path}");
        }
    }
}
