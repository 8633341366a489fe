//! Bounded property tests: truncations and byte mutations of the real maps never panic; they import or fail with
//! an error that names the file.

use mapc_import::{ImportOptions, MapFormat, import_bytes};
use proptest::prelude::*;
use std::path::PathBuf;
use std::sync::OnceLock;

fn bytes(name: &str) -> &'static [u8] {
    static CACHE: OnceLock<Vec<(String, Vec<u8>)>> = OnceLock::new();
    let all = CACHE.get_or_init(|| {
        [
            "i696.osm",
            "i696.osm.pbf",
            "simple_merge.net.xml",
            "us_merge.net.xml",
        ]
        .iter()
        .map(|n| {
            let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../maps")
                .join(n);
            (n.to_string(), std::fs::read(p).unwrap())
        })
        .collect()
    });
    &all.iter().find(|(n, _)| n == name).unwrap().1
}

fn mutate(data: &[u8], cut: f64, flips: &[(f64, u8)]) -> Vec<u8> {
    let mut v = data[..((data.len() as f64 * cut) as usize).min(data.len())].to_vec();
    let n = v.len();
    if n > 0 {
        for &(at, x) in flips {
            let i = ((n as f64 * at) as usize).min(n - 1);
            v[i] ^= x;
        }
    }
    v
}

fn never_panics(name: &str, format: MapFormat, data: &[u8]) {
    match import_bytes(data, format, name, &ImportOptions::default()) {
        Ok(g) => assert!(g.invariant_violations().is_empty()),
        Err(e) => assert!(e.to_string().starts_with(name), "{e}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn sumo_mutations(which in 0..2usize, cut in 0.0..1.0f64, flips in prop::collection::vec((0.0..1.0f64, 1..=255u8), 0..6)) {
        let name = ["simple_merge.net.xml", "us_merge.net.xml"][which];
        never_panics(name, MapFormat::SumoNet, &mutate(bytes(name), cut, &flips));
    }

    #[test]
    fn pbf_mutations(cut in 0.0..1.0f64, flips in prop::collection::vec((0.0..1.0f64, 1..=255u8), 0..4)) {
        never_panics("i696.osm.pbf", MapFormat::OsmPbf, &mutate(bytes("i696.osm.pbf"), cut, &flips));
    }
}

proptest! {
    // The OSM file is 3.4 MB: fewer cases, each reading at most the first tenth of it plus its tail.
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn osm_mutations(cut in 0.0..0.1f64, flips in prop::collection::vec((0.0..1.0f64, 1..=255u8), 0..6)) {
        let all = bytes("i696.osm");
        let mut data = mutate(all, cut, &flips);
        // Keep the well-formed tail sometimes, so that some cases get through to the graph builder.
        if flips.len() % 2 == 0 {
            data.extend_from_slice(b"\n</osm>\n");
        }
        never_panics("i696.osm", MapFormat::OsmXml, &data);
    }
}
