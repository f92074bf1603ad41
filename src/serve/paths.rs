//! Which file a request path names, if any: the preview's path safety. Owns
//! the route table (every output of the config at its path relative to the
//! config's folder, `/out/grid.html` for `out/grid.html`, so the preview
//! mirrors the files; an output outside that folder under `/<dataset>/<file
//! name>`, where every output was served before, which now redirects;
//! nothing else), the strict decoding of a request path, and the
//! check that the file found is still inside its output folder (a symlink
//! placed there pointing out of it is refused). There is no directory
//! listing and no path arithmetic: a decoded path is looked up as a whole in
//! the table, so `..`, absolute paths and encoded tricks can only miss.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use crate::config::Config;
use crate::render::OutputKind;
use crate::workspace;

/// One servable file.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Route {
    /// The dataset it belongs to.
    pub(crate) dataset: String,
    /// The output file, as the config resolves it.
    pub(crate) file: PathBuf,
    /// What it is (decides the content type and whether the live script goes in).
    pub(crate) kind: OutputKind,
}

/// The config's outputs by URL path, read again when the config file changes.
#[derive(Debug, Default)]
pub(crate) struct Routes {
    config_path: PathBuf,
    stamp: Option<SystemTime>,
    /// URL path (decoded, starting with `/`) to file.
    pub(crate) by_path: BTreeMap<String, Route>,
    /// Dataset names in config order, each with its URL paths.
    pub(crate) datasets: Vec<(String, Vec<String>)>,
    /// The URL paths outputs were served at before (`/<dataset>/<file
    /// name>`), to the path they are served at now.
    pub(crate) moved: BTreeMap<String, String>,
}

impl Routes {
    /// The routes of the config at `config_path` (empty if it cannot be read:
    /// the daemon reports why).
    pub(crate) fn new(config_path: &Path) -> Routes {
        let mut routes = Routes {
            config_path: config_path.to_path_buf(),
            ..Routes::default()
        };
        routes.refresh();
        routes
    }

    /// Reads the config again if its modification time changed; a config
    /// that does not parse keeps the last good routes (as the daemon keeps
    /// the last good config).
    pub(crate) fn refresh(&mut self) {
        let stamp = workspace::modified(&self.config_path);
        if stamp.is_some() && stamp == self.stamp {
            return;
        }
        self.stamp = stamp;
        if let Ok(config) = Config::from_path(&self.config_path) {
            self.set(&config);
        }
    }

    fn set(&mut self, config: &Config) {
        self.by_path.clear();
        self.datasets.clear();
        self.moved.clear();
        let mut old_urls: Vec<(String, String)> = Vec::new();
        for d in &config.datasets {
            let mut urls = Vec::new();
            for out in &d.outputs {
                let (Some(kind), Some(name)) = (out.kind, out.path.file_name()) else {
                    continue;
                };
                let old = format!("/{}/{}", d.name, name.to_string_lossy());
                let url = mirrored(&d.base, &out.path).unwrap_or_else(|| old.clone());
                // Two outputs at one URL (an output outside the config's
                // folder named like another): the first is served.
                if self.by_path.contains_key(&url) {
                    continue;
                }
                self.by_path.insert(
                    url.clone(),
                    Route {
                        dataset: d.name.clone(),
                        file: out.path.clone(),
                        kind,
                    },
                );
                if old != url {
                    old_urls.push((old, url.clone()));
                }
                urls.push(url);
            }
            self.datasets.push((d.name.clone(), urls));
        }
        // An old URL that is now some output's own path stays that output.
        for (old, url) in old_urls {
            if !self.by_path.contains_key(&old) {
                self.moved.entry(old).or_insert(url);
            }
        }
    }

    /// The URL path of the first HTML output in config order, else `/`.
    pub(crate) fn first_page(&self) -> String {
        self.datasets
            .iter()
            .flat_map(|(_, urls)| urls)
            .find(|u| self.by_path.get(*u).is_some_and(|r| r.kind == OutputKind::Html))
            .cloned()
            .unwrap_or_else(|| "/".to_string())
    }

    /// Where an output served at `target` before is now (`/grid/grid.html`
    /// to `/out/grid.html`), for a permanent redirect.
    pub(crate) fn moved(&self, target: &str) -> Option<&str> {
        self.moved.get(&decode(target)?).map(String::as_str)
    }

    /// The route a raw request target (path and query, as sent) names.
    pub(crate) fn find(&self, target: &str) -> Option<&Route> {
        self.by_path.get(&decode(target)?)
    }
}

/// The URL path of `file` relative to the config's folder `base`
/// (`/out/grid.html`), when it lies inside it along plain names (no `..`).
fn mirrored(base: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(base).ok()?;
    let mut url = String::new();
    for part in rel.components() {
        let std::path::Component::Normal(name) = part else {
            return None;
        };
        url.push('/');
        url.push_str(name.to_str()?);
    }
    // Whatever `decode` refuses could never be asked for.
    (!url.is_empty() && decode(&encode(&url)).as_deref() == Some(url.as_str())).then_some(url)
}

/// The path of a request target, percent-decoded, or `None` for anything
/// that is not a plain absolute path: no query is kept; a bad escape, a
/// non-UTF-8 result, a NUL, a backslash, an empty, `.` or `..` segment (a
/// `//`), are refused outright rather than normalised.
pub(crate) fn decode(target: &str) -> Option<String> {
    let path = target.split(['?', '#']).next()?;
    if !path.starts_with('/') {
        return None;
    }
    let raw = path.as_bytes();
    let mut bytes = Vec::with_capacity(raw.len());
    let mut i = 0;
    while i < raw.len() {
        if raw[i] == b'%' {
            let hex = std::str::from_utf8(raw.get(i + 1..i + 3)?).ok()?;
            bytes.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            bytes.push(raw[i]);
            i += 1;
        }
    }
    let text = String::from_utf8(bytes).ok()?;
    if text.contains(['\0', '\\']) {
        return None;
    }
    let ok = text[1..].is_empty()
        || text[1..]
            .split('/')
            .all(|seg| !seg.is_empty() && seg != "." && seg != "..");
    ok.then_some(text)
}

/// The file of `route` if it is a regular file inside its own output folder
/// once every symlink is resolved; `None` otherwise (a symlink placed there
/// pointing elsewhere, a folder, a missing file).
pub(crate) fn inside(route: &Route) -> Option<PathBuf> {
    let folder = workspace::canonical(route.file.parent()?)?;
    let real = workspace::canonical(&route.file)?;
    (real.starts_with(&folder) && workspace::is_file(&real)).then_some(real)
}

/// A URL path segment of `text`, percent-encoded where needed.
pub(crate) fn encode(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for b in text.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            out.push(char::from(b));
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_paths_decode_and_tricks_do_not() {
        assert_eq!(decode("/a/b.html?x=1").as_deref(), Some("/a/b.html"));
        assert_eq!(decode("/a%20b/c.svg").as_deref(), Some("/a b/c.svg"));
        assert_eq!(decode("/").as_deref(), Some("/"));
        for bad in [
            "/../etc/passwd",
            "/a/../b",
            "/%2e%2e/etc/passwd",
            "/%2E%2E/x",
            "/a/%2e/b",
            "//etc/passwd",
            "/a\\..\\b",
            "/a%5c..%5cb",
            "/a%00b",
            "/a%zz",
            "/a%2",
            "etc/passwd",
            "http://x/a",
            "/%ff",
        ] {
            assert_eq!(decode(bad), None, "{bad}");
        }
    }

    #[test]
    fn only_outputs_are_routes() {
        let dir = tempfile::tempdir().expect("temp dir");
        let config = dir.path().join("c.yaml");
        std::fs::write(
            &config,
            "datasets:\n  - name: d\n    format: hierarchy-json\n    files: {hierarchy: h.json}\n    \
             outputs: [out/d.html, out/d.svg, ../elsewhere/e.png, top.json]\n",
        )
        .expect("write");
        let routes = Routes::new(&config);
        // At their paths in the config's folder; one outside it where all
        // were served before.
        assert_eq!(
            routes.datasets,
            vec![(
                "d".to_string(),
                vec![
                    "/out/d.html".to_string(),
                    "/out/d.svg".to_string(),
                    "/d/e.png".to_string(),
                    "/top.json".to_string()
                ]
            )]
        );
        assert!(routes.find("/out/d.html").is_some());
        assert!(routes.find("/d/h.json").is_none());
        assert!(routes.find("/out/../c.yaml").is_none());
        assert!(routes.find("/out/%64.html").is_some(), "an escaped letter is the letter");
        // The old URLs redirect; nothing else does.
        assert_eq!(routes.moved("/d/d.html"), Some("/out/d.html"));
        assert_eq!(routes.moved("/d/top.json"), Some("/top.json"));
        assert_eq!(routes.moved("/d/e.png"), None, "still served there");
        assert_eq!(routes.moved("/d/c.yaml"), None);
        assert_eq!(routes.moved("/d/../d/d.html"), None);
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_out_of_the_folder_is_refused() {
        let dir = tempfile::tempdir().expect("temp dir");
        let out = dir.path().join("out");
        std::fs::create_dir(&out).expect("mkdir");
        std::fs::write(dir.path().join("secret"), "x").expect("write");
        std::os::unix::fs::symlink(dir.path().join("secret"), out.join("d.svg")).expect("link");
        std::fs::write(out.join("d.html"), "x").expect("write");
        let route = |name: &str| Route {
            dataset: "d".to_string(),
            file: out.join(name),
            kind: OutputKind::Svg,
        };
        assert_eq!(inside(&route("d.svg")), None);
        assert!(inside(&route("d.html")).is_some());
    }
}
