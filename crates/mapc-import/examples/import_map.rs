//! Import one map and print its summary: what `mapc import` does, without the rest of the binary, for
//! `/usr/bin/time -v` measurements (docs/perf_import.md).

fn main() {
    let Some(path) = std::env::args_os().nth(1) else {
        eprintln!("usage: import_map MAP");
        std::process::exit(2);
    };
    match mapc_import::import_path(
        std::path::Path::new(&path),
        &mapc_import::ImportOptions::default(),
    ) {
        Ok(g) => println!(
            "{}",
            serde_json::to_string(&mapc_import::Summary::of(&g)).unwrap()
        ),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
