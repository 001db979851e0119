//! The page's files, embedded in the binary: the page works with no network at all. Chart.js
//! (MIT, its licence beside it in `page/vendor/`) is the npm package's UMD build, committed as
//! published.

/// One embedded file.
pub struct Asset {
    pub content_type: &'static str,
    pub bytes: &'static [u8],
}

const FILES: [(&str, &str, &[u8]); 8] = [
    (
        "/",
        "text/html; charset=utf-8",
        include_bytes!("../page/index.html"),
    ),
    (
        "/bicycle",
        "text/html; charset=utf-8",
        include_bytes!("../page/bicycle.html"),
    ),
    (
        "/common.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../page/common.js"),
    ),
    (
        "/app.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../page/app.js"),
    ),
    (
        "/bicycle.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../page/bicycle.js"),
    ),
    (
        "/style.css",
        "text/css; charset=utf-8",
        include_bytes!("../page/style.css"),
    ),
    (
        "/vendor/chart.umd.min.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../page/vendor/chart.umd.min.js"),
    ),
    (
        "/vendor/chart.js-LICENSE.md",
        "text/plain; charset=utf-8",
        include_bytes!("../page/vendor/chart.js-LICENSE.md"),
    ),
];

/// The file served at `path` (`/index.html` is `/`, `/bicycle.html` is `/bicycle`).
pub fn get(path: &str) -> Option<Asset> {
    let path = match path {
        "/index.html" => "/",
        "/bicycle.html" => "/bicycle",
        other => other,
    };
    FILES
        .iter()
        .find(|(p, _, _)| *p == path)
        .map(|(_, content_type, bytes)| Asset {
            content_type,
            bytes,
        })
}
