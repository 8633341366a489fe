//! Headless Chromium for the tests of `mapc view`'s page (Debian's package; `.ci/run` installs it). The page
//! writes what it drew into `#mapc-status`, which `--dump-dom` prints with the rest of the page as it stands.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Chromium (`MAPC_CHROMIUM`, else on PATH). Without it a test says so and passes, except in CI (`CI` set),
/// where it fails: CI must run the browser tests.
pub fn chromium_or_skip(test: &str) -> Option<PathBuf> {
    let found = std::env::var_os("MAPC_CHROMIUM")
        .map(PathBuf::from)
        .or_else(|| {
            let path = std::env::var_os("PATH")?;
            ["chromium", "chromium-browser", "google-chrome"]
                .iter()
                .flat_map(|name| std::env::split_paths(&path).map(move |d| d.join(name)))
                .find(|p| p.is_file())
        });
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs Chromium for the browser tests (.ci/run installs Debian's chromium)"
        );
        eprintln!(
            "{test} skipped: no chromium on PATH (apt-get install chromium, or set MAPC_CHROMIUM)"
        );
    }
    found
}

/// Run headless Chromium on `url` with `extra` arguments; its own profile folder, so parallel runs do not meet.
/// Returns what it printed (the DOM, with `--dump-dom`).
pub fn browse(browser: &Path, profile: &Path, url: &str, extra: &[&str]) -> String {
    let out = Command::new("timeout")
        .arg("180")
        .arg(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--no-first-run",
            "--window-size=1400,1000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(url)
        .output()
        .expect("chromium runs");
    assert!(
        out.status.success(),
        "chromium failed on {url}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The opening tag of the element with `id` in a dumped DOM.
pub fn opening_tag<'a>(dom: &'a str, id: &str) -> &'a str {
    let at = dom
        .find(&format!("id=\"{id}\""))
        .unwrap_or_else(|| panic!("no #{id} in the page: {}", &dom[..dom.len().min(400)]));
    let start = dom[..at].rfind('<').unwrap();
    &dom[start..at + dom[at..].find('>').unwrap() + 1]
}

/// The `data-NAME` attribute of the page's status element in a dumped DOM, as the page set it.
pub fn status_attr(dom: &str, name: &str) -> String {
    let tag = opening_tag(dom, "mapc-status");
    let key = format!("data-{name}=\"");
    let start = tag
        .find(&key)
        .unwrap_or_else(|| panic!("the page wrote no data-{name}: {tag}"))
        + key.len();
    unescape(&tag[start..start + tag[start..].find('"').unwrap()])
}

/// Text as the page holds it, from its serialisation in a dumped DOM (which escapes `&`, `<`, `>`, `"` and
/// no-break spaces).
pub fn unescape(serialised: &str) -> String {
    serialised
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&nbsp;", "\u{a0}")
        .replace("&amp;", "&")
}
