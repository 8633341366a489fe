//! `cargo bench -p mapc-import`: import the real maps (the figures in docs/perf_import.md).

use criterion::{Criterion, criterion_group, criterion_main};
use mapc_import::{ImportOptions, import_path};
use std::path::PathBuf;

fn maps(c: &mut Criterion) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../maps");
    let options = ImportOptions::default();
    let mut group = c.benchmark_group("import");
    group.sample_size(20);
    for name in ["i696.osm", "i696.osm.pbf", "i696_onelane_proxy.net.xml"] {
        let path = dir.join(name);
        group.bench_function(name, |b| b.iter(|| import_path(&path, &options).unwrap()));
    }
    group.finish();
}

criterion_group!(benches, maps);
criterion_main!(benches);
