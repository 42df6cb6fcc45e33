//! The layout's rules, checked: no module of any crate imports a module
//! that imports it back (`../shared/tools/mod_cycles.py`, run on every
//! crate's sources; without `../shared` this fails, as CI must).

use std::path::Path;

#[test]
fn no_crate_has_module_circles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tool = root.join("../shared/tools/mod_cycles.py");
    assert!(tool.is_file(), "{} is missing: ../shared must sit beside the project", tool.display());
    let mut dirs: Vec<_> = std::fs::read_dir(root.join("crates")).unwrap().flatten().map(|e| e.path().join("src")).collect();
    dirs.push(root.join("tools/fuzz-targets/src"));
    dirs.push(root.join("python/src"));
    dirs.sort();
    assert!(dirs.len() >= 12, "{dirs:?}");
    for d in dirs {
        let o = std::process::Command::new("python3").arg(&tool).arg(&d).output().expect("python3 runs the layout tool");
        assert!(o.status.success(), "{}: module circles:\n{}{}", d.display(), String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    }
}
