//! `mapc view` on maps whose text is HTML and script. Maps come from the internet: a road's class, name or id, a
//! scenario's name and its vehicle types are whatever their author wrote. Headless Chromium (`common::browser`)
//! opens pages made from such files and they run none of it (no `data-pwned` on the body), load nothing (a probe
//! on the loopback interface sees no connection), and show every such string as text; a script added to a page
//! afterwards does not run either, as the page's Content-Security-Policy allows only its own.

use base64::Engine;
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::io::{BufRead, BufReader, Read};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

mod common;

use common::browser::{browse, chromium_or_skip, opening_tag, status_attr, unescape};
use common::{assert_success, root, run_mapc as mapc, scratch_dir};

/// Each of these, taken as HTML, sets `data-pwned` on the body or ends the element it stands in.
const IMG: &str = "<img src=x onerror=document.body.dataset.pwned=1>";
const CLOSE_SCRIPT: &str = "</script><script>document.body.dataset.pwned=2</script>";
const COMMENT: &str = "<!--<script>";
/// Ids without white space (SUMO lists lane ids separated by spaces).
const ID_SVG: &str = "<svg/onload=document.body.dataset.pwned=3>";
const ID_IMG: &str = "<img/src/onerror=document.body.dataset.pwned=4>";
/// Already escaped once: shown as these characters, not as a tag.
const ID_ENTITY: &str = "&lt;script&gt;document.body.dataset.pwned=5&lt;/script&gt;";
const NAME: &str = "<img src=x onerror=document.body.dataset.pwned=6> scenario\u{2028}";
const VEHICLE_TYPE: &str = "<b onmouseover=document.body.dataset.pwned=7>human</b>";

/// A listener on the loopback interface that counts connections, and requests (connections that sent something):
/// text that loads from it reached the network.
struct Probe {
    port: u16,
    connections: Arc<AtomicUsize>,
    requests: Arc<AtomicUsize>,
}

impl Probe {
    fn start() -> Probe {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let connections = Arc::new(AtomicUsize::new(0));
        let requests = Arc::new(AtomicUsize::new(0));
        let (c, r) = (connections.clone(), requests.clone());
        std::thread::spawn(move || {
            for stream in listener.incoming() {
                c.fetch_add(1, Ordering::SeqCst);
                let r = r.clone();
                std::thread::spawn(move || {
                    let mut byte = [0u8; 1];
                    if let Ok(mut stream) = stream {
                        let _ = stream.set_read_timeout(Some(Duration::from_secs(5)));
                        if matches!(stream.read(&mut byte), Ok(1)) {
                            r.fetch_add(1, Ordering::SeqCst);
                        }
                    }
                });
            }
        });
        Probe {
            port,
            connections,
            requests,
        }
    }

    /// Markup that loads from the probe (an image, a frame, a style sheet).
    fn loader(&self) -> String {
        let at = format!("http://127.0.0.1:{}", self.port);
        format!(
            "<img src={at}/img><iframe src={at}/frame></iframe><link rel=stylesheet href={at}/css>"
        )
    }

    /// (connections, requests) so far, once the last connection has had a moment to say something.
    fn seen(&self) -> (usize, usize) {
        std::thread::sleep(Duration::from_millis(300));
        (
            self.connections.load(Ordering::SeqCst),
            self.requests.load(Ordering::SeqCst),
        )
    }
}

/// Text for an XML attribute value.
fn xml_attr(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The Simple Merge network (`maps/simple_merge.net.xml`) with hostile types, ids and a
/// name: `highwayType` and `mergeType` become [`IMG`] and [`CLOSE_SCRIPT`], the edges and junctions `left`,
/// `center` and `bottom` (and so their lanes) [`ID_SVG`], [`ID_IMG`] and [`ID_ENTITY`], and the edge `center`
/// is named [`COMMENT`] and the probe's loader.
fn hostile_net(probe: &Probe) -> String {
    let net = std::fs::read_to_string(root().join("maps/simple_merge.net.xml")).unwrap();
    let named = format!(
        "<edge name=\"{}\" id=\"center\"",
        xml_attr(&format!("{COMMENT} {}", probe.loader()))
    );
    assert!(
        net.contains("<edge id=\"center\""),
        "maps/simple_merge.net.xml"
    );
    net.replace("<edge id=\"center\"", &named)
        .replace("highwayType", &xml_attr(IMG))
        .replace("mergeType", &xml_attr(CLOSE_SCRIPT))
        .replace("left", &xml_attr(ID_SVG))
        .replace("center", &xml_attr(ID_IMG))
        .replace("bottom", &xml_attr(ID_ENTITY))
}

/// An OSM way: its id, its nodes and its tags.
type OsmWay<'a> = (i64, &'a [i64], [(&'a str, &'a str); 4]);

/// A small OSM map: a motorway with an on-ramp, its names and refs hostile.
fn hostile_osm(probe: &Probe) -> String {
    let nodes = [
        (1, 42.5000, -83.3100),
        (2, 42.5000, -83.3000),
        (3, 42.5000, -83.2900),
        (4, 42.5000, -83.2800),
        (5, 42.5000, -83.2700),
        (6, 42.4950, -83.3050),
        (7, 42.4980, -83.2950),
    ];
    let mut osm =
        String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<osm version=\"0.6\">\n");
    for (id, lat, lon) in nodes {
        osm += &format!("  <node id=\"{id}\" lat=\"{lat}\" lon=\"{lon}\"/>\n");
    }
    let loader = probe.loader();
    let ways: [OsmWay; 3] = [
        (
            10,
            &[1, 2, 3],
            [
                ("highway", "motorway"),
                ("name", IMG),
                ("ref", CLOSE_SCRIPT),
                ("maxspeed", COMMENT),
            ],
        ),
        (
            11,
            &[3, 4, 5],
            [
                ("highway", "motorway"),
                ("name", &loader),
                ("ref", ID_ENTITY),
                ("lanes", "2"),
            ],
        ),
        (
            12,
            &[6, 7, 3],
            [
                ("highway", "motorway_link"),
                ("name", ID_SVG),
                ("ref", "\u{2028}</SCRIPT>"),
                ("oneway", "yes"),
            ],
        ),
    ];
    for (id, refs, tags) in ways {
        osm += &format!("  <way id=\"{id}\">\n");
        for r in refs {
            osm += &format!("    <nd ref=\"{r}\"/>\n");
        }
        for (k, v) in tags {
            osm += &format!("    <tag k=\"{k}\" v=\"{}\"/>\n", xml_attr(v));
        }
        osm += "  </way>\n";
    }
    osm + "</osm>\n"
}

/// The Simple Merge scenario on the hostile net, itself named [`NAME`], its humans of type [`VEHICLE_TYPE`].
fn hostile_scenario(net_file: &str) -> String {
    let source = std::fs::read_to_string(root().join("scenarios/simple_merge.toml")).unwrap();
    let (head, rest) = source.split_at(source.find("[network.simple_merge]").unwrap());
    let rest = &rest[rest.find("[vehicle_types.").unwrap()..];
    let quoted = toml_string(VEHICLE_TYPE);
    format!("{head}[network]\nmap = {}\n\n{rest}", toml_string(net_file))
        .replace(
            "name = \"simple_merge\"",
            &format!("name = {}", toml_string(NAME)),
        )
        .replace(
            "[vehicle_types.human]",
            &format!("[vehicle_types.{quoted}]"),
        )
        .replace(
            "vehicle_type = \"human\"",
            &format!("vehicle_type = {quoted}"),
        )
}

fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// What a page shows as text (the DOM's serialisation of an element's content, its tags dropped).
fn text_of(dom: &str, id: &str) -> String {
    let tag = opening_tag(dom, id);
    let name: String = tag[1..]
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric())
        .collect();
    let start = dom.find(tag).unwrap() + tag.len();
    let inner = &dom[start..start + dom[start..].find(&format!("</{name}>")).unwrap()];
    let mut text = String::new();
    let mut in_tag = false;
    for c in inner.chars() {
        match c {
            '<' => in_tag = true,
            '>' if in_tag => in_tag = false,
            c if !in_tag => text.push(c),
            _ => {}
        }
    }
    unescape(&text)
}

/// The page's embedded data, read as its script reads it.
fn page_data(html: &str) -> Value {
    let start = html.find("id=\"mapc-data\">").unwrap() + "id=\"mapc-data\">".len();
    serde_json::from_str(&html[start..start + html[start..].find("</script>").unwrap()]).unwrap()
}

/// The id (`R3`, `J2`) of the road or junction whose provenance names SUMO element `sumo_id`.
fn element_from(data: &Value, list: &str, sumo_id: &str) -> String {
    let wanted = format!("sumo:{sumo_id}");
    data["network"][list]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["provenance"].as_str().unwrap().contains(&wanted))
        .unwrap_or_else(|| panic!("no {list} from {sumo_id}"))["id"]
        .as_str()
        .unwrap()
        .to_string()
}

/// Checks every dumped page must pass: its own script ran, nothing else did, and nothing was added to it.
fn assert_inert(dom: &str, what: &str) {
    assert!(
        !dom.contains("data-pwned"),
        "{what}: map text ran as script: {}",
        opening_tag(dom, "mapc-status")
    );
    let frames: u64 = status_attr(dom, "frames-drawn").parse().unwrap();
    assert!(frames >= 1, "{what}: the page's own script did not draw");
    // the page's own elements only: its data block and script, its style sheet, nothing loaded
    let data_start = dom.find("id=\"mapc-data\">").map(|at| at + 15);
    let outside_data = match data_start {
        Some(s) => format!(
            "{}{}",
            &dom[..s],
            &dom[s + dom[s..].find("</script>").unwrap()..]
        ),
        None => dom.to_string(),
    };
    let expected_scripts = if data_start.is_some() { 2 } else { 1 };
    assert_eq!(
        outside_data.matches("<script").count(),
        expected_scripts,
        "{what}: {dom}"
    );
    assert_eq!(outside_data.matches("<style").count(), 1, "{what}");
    for tag in ["<img", "<svg", "<iframe", "<link", "<b "] {
        assert!(
            !outside_data.contains(tag),
            "{what}: a map made a {tag} element"
        );
    }
}

fn hover_text(dom: &str) -> String {
    status_attr(dom, "hover")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

struct Pages {
    browser: PathBuf,
    dir: PathBuf,
    opened: usize,
}

impl Pages {
    /// The DOM of `page#fragment` after its script ran (`budget_ms` of the browser's virtual time).
    fn open(&mut self, url: &str, budget_ms: u32) -> String {
        self.opened += 1;
        browse(
            &self.browser,
            &self.dir.join(format!("profile-{}", self.opened)),
            url,
            &[&format!("--virtual-time-budget={budget_ms}"), "--dump-dom"],
        )
    }
}

fn file_url(page: &Path, fragment: &str) -> String {
    format!("file://{}#{fragment}", page.display())
}

#[test]
fn map_text_in_every_field_shows_as_text_and_runs_nothing_in_chromium() {
    let Some(browser) =
        chromium_or_skip("map_text_in_every_field_shows_as_text_and_runs_nothing_in_chromium")
    else {
        return;
    };
    let dir = scratch_dir("view-hostile");
    let probe = Probe::start();
    let mut pages = Pages {
        browser,
        dir: dir.clone(),
        opened: 0,
    };

    // a SUMO net, its file name hostile too
    let net = dir.join(format!("{IMG}.net.xml"));
    std::fs::write(&net, hostile_net(&probe)).unwrap();
    let page = dir.join("net.html");
    assert_success(&mapc(&["view", s(&net), "-o", s(&page)]));
    let html = std::fs::read_to_string(&page).unwrap();
    let data = page_data(&html);
    let center = element_from(&data, "roads", ID_IMG);
    let ramp = element_from(&data, "roads", ID_ENTITY);
    let left = element_from(&data, "junctions", ID_SVG);

    let dom = pages.open(&file_url(&page, &format!("hover={center}")), 5000);
    assert_inert(&dom, "SUMO net, road");
    let legend = text_of(&dom, "legend");
    assert!(
        legend.contains(IMG) && legend.contains(CLOSE_SCRIPT),
        "the road classes are the legend's text: {legend}"
    );
    assert!(text_of(&dom, "title").contains(IMG), "{dom}");
    let tip = hover_text(&dom);
    assert!(
        tip.starts_with(&format!("road {center} · {COMMENT} {}", probe.loader()))
            && tip.contains(&format!("({IMG})"))
            && tip.contains(&format!("sumo:{ID_IMG}")),
        "{tip}"
    );
    assert_eq!(text_of(&dom, "tip"), tip, "the tooltip shows the same text");

    let dom = pages.open(&file_url(&page, &format!("hover={ramp}")), 5000);
    assert_inert(&dom, "SUMO net, ramp");
    let tip = hover_text(&dom);
    assert!(
        tip.contains(&format!("({CLOSE_SCRIPT})")) && tip.contains(&format!("sumo:{ID_ENTITY}")),
        "{tip}"
    );
    let dom = pages.open(&file_url(&page, &format!("hover={left}")), 5000);
    assert_inert(&dom, "SUMO net, junction");
    let tip = hover_text(&dom);
    assert!(
        tip.starts_with(&format!("junction {left} · ")) && tip.contains(&format!("sumo:{ID_SVG}")),
        "{tip}"
    );

    // the same net as a scenario, played: its name, vehicle type and window are text too
    let scenario = dir.join("hostile.toml");
    std::fs::write(&scenario, hostile_scenario(s(&net))).unwrap();
    let replay = dir.join("replay.html");
    assert_success(&mapc(&["view", s(&scenario), "-o", s(&replay)]));
    let dom = pages.open(&file_url(&replay, "t=0&hover=0&play&rate=50"), 40000);
    assert_inert(&dom, "scenario");
    assert_eq!(status_attr(&dom, "frame"), "2000", "played to the end");
    assert!(
        text_of(&dom, "title").starts_with(NAME),
        "{}",
        text_of(&dom, "title")
    );
    let tip = hover_text(&dom);
    assert!(
        tip.starts_with(&format!("vehicle 0 · {VEHICLE_TYPE}")),
        "{tip}"
    );
    assert!(text_of(&dom, "legend").contains(IMG));

    // an OSM map with hostile names, refs and tags
    let osm = dir.join("hostile.osm");
    std::fs::write(&osm, hostile_osm(&probe)).unwrap();
    let osm_page = dir.join("osm.html");
    assert_success(&mapc(&["view", s(&osm), "-o", s(&osm_page)]));
    let data = page_data(&std::fs::read_to_string(&osm_page).unwrap());
    let roads = data["network"]["roads"].as_array().unwrap();
    let first = roads
        .iter()
        .find(|r| r["provenance"].as_str().unwrap().contains("osm-way:10"))
        .expect("way 10 is a road");
    assert_eq!(first["label"], format!("{CLOSE_SCRIPT} {IMG}"));
    let id = first["id"].as_str().unwrap();
    let dom = pages.open(&file_url(&osm_page, &format!("hover={id}")), 5000);
    assert_inert(&dom, "OSM map");
    let tip = hover_text(&dom);
    assert!(
        tip.starts_with(&format!("road {id} · {CLOSE_SCRIPT} {IMG} (motorway)")),
        "{tip}"
    );

    // served: the page fetches its data from where it came (its policy allows that and nothing more)
    let mut child = common::mapc_command()
        .args(["view", s(&net), "--serve"])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first_line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first_line)
        .unwrap();
    let address = first_line
        .split("http://")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .unwrap_or_else(|| panic!("no address in `{first_line}`"))
        .to_string();
    let dom = pages.open(&format!("http://{address}/#hover={center}"), 5000);
    child.kill().unwrap();
    child.wait().unwrap();
    assert_inert(&dom, "served page");
    assert!(text_of(&dom, "legend").contains(IMG));
    assert!(hover_text(&dom).contains(&format!("sumo:{ID_IMG}")));

    assert_eq!(probe.seen(), (0, 0), "a page reached the network");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_script_added_to_the_page_does_not_run_as_its_policy_names_only_its_own() {
    let Some(browser) = chromium_or_skip(
        "a_script_added_to_the_page_does_not_run_as_its_policy_names_only_its_own",
    ) else {
        return;
    };
    let dir = scratch_dir("view-csp");
    let probe = Probe::start();
    let page = dir.join("map.html");
    assert_success(&mapc(&["view", "maps/us_merge.net.xml", "-o", s(&page)]));
    let html = std::fs::read_to_string(&page).unwrap();

    // the policy in the page names the SHA-256 of the page's own script, as it stands in the file
    let meta = "<meta http-equiv=\"Content-Security-Policy\" content=\"";
    let policy_at = html
        .find(meta)
        .expect("the page carries a Content-Security-Policy");
    let policy = &html[policy_at + meta.len()..];
    let policy = &policy[..policy.find('"').unwrap()];
    let script_at = html.rfind("<script>").unwrap() + "<script>".len();
    let script = &html[script_at..script_at + html[script_at..].find("</script>").unwrap()];
    let hash = base64::engine::general_purpose::STANDARD.encode(Sha256::digest(script.as_bytes()));
    assert!(
        policy.contains(&format!("script-src 'sha256-{hash}';")),
        "{policy}"
    );
    for directive in [
        "default-src 'none'",
        "connect-src 'none'",
        "base-uri 'none'",
    ] {
        assert!(policy.contains(directive), "{policy}");
    }

    // a script, an event handler and a load added to the file after it was written
    let added = format!(
        "<script>document.body.dataset.pwned = 'inline'</script>\
         <img src=x onerror=\"document.body.dataset.pwned = 'handler'\">{}\n</body>",
        probe.loader()
    );
    let tampered = dir.join("tampered.html");
    std::fs::write(&tampered, html.replacen("</body>", &added, 1)).unwrap();
    let dom = browse(
        &browser,
        &dir.join("profile"),
        &format!("file://{}", tampered.display()),
        &["--virtual-time-budget=5000", "--dump-dom"],
    );
    assert!(
        !dom.contains("data-pwned"),
        "{}",
        opening_tag(&dom, "mapc-status")
    );
    let frames: u64 = status_attr(&dom, "frames-drawn").parse().unwrap();
    assert!(frames >= 1, "the page's own script still runs");
    // Chromium may open a bare connection ahead of a frame that the policy then refuses: no request is sent
    assert_eq!(
        probe.seen().1,
        0,
        "the added markup loaded from the network"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
