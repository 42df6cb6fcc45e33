//! The bodies of mint's fuzz targets, in one place for both their users:
//! the cargo-fuzz crate in `tools/fuzz` (nightly, libFuzzer, long runs by
//! hand) and the stable replay test `tests/fuzz_replay.rs` (CI), which runs
//! every file of `tools/fuzz/corpus/<target>/` and
//! `tools/fuzz/regressions/<target>/` through [`run`], plus a short
//! deterministic mutation smoke ([`mutate`]).
//!
//! A target takes any bytes. It fails by panicking: on a panic of the
//! library, or when a check of the output's internal consistency fails.
//! Errors (`Err`) are fine, as long as they keep the error contract of
//! docs/INVARIANTS.md: one non-empty line naming the file.

use std::cell::RefCell;
use std::path::{Path, PathBuf};

pub mod mutate;

/// A target: its name (the directory under `corpus/` and `regressions/`,
/// and the cargo-fuzz target) and its body.
pub type Target = (&'static str, fn(&[u8]));

/// Every target.
pub const TARGETS: &[Target] = &[
    ("read_ply", read_ply),
    ("read_obj", read_obj),
    ("read_stl", read_stl),
    ("read_off", read_off),
    ("read_mesh", read_mesh),
    ("read_raw", read_raw),
    ("read_wrl", read_wrl),
    ("read_3ds", read_3ds),
    ("read_glb", read_glb),
    ("read_gltf", read_gltf),
    ("read_list", read_list),
    ("read_tileset", read_tileset),
    ("read_pro", read_pro),
    ("read_conf", read_conf),
    ("read_aln", read_aln),
    ("read_rgrid", read_rgrid),
    ("parse_scene", parse_scene),
    ("read_plan", read_plan),
    ("stage", stage),
    ("discretize", discretize),
    ("resample", resample),
    ("simplify", simplify),
    ("read_nrrd", read_nrrd),
    ("read_metaimage", read_metaimage),
    ("read_nifti", read_nifti),
    ("read_dicom_volume", read_dicom_volume),
    ("read_tiff_volume", read_tiff_volume),
    ("volume", volume),
];

/// The target named `name`.
pub fn target(name: &str) -> Option<fn(&[u8])> {
    TARGETS.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}

/// Runs target `name` on `data`; panics on an unknown name.
pub fn run(name: &str, data: &[u8]) {
    target(name).unwrap_or_else(|| panic!("no fuzz target named {name:?}"))(data)
}

thread_local! {
    static DIR: RefCell<Option<tempfile::TempDir>> = const { RefCell::new(None) };
}

/// A scratch directory of this thread, made once, removed at exit; in
/// memory (`/dev/shm`) when there is one, where the writers' `fsync`s cost
/// nothing.
fn scratch() -> PathBuf {
    DIR.with(|d| {
        let mut d = d.borrow_mut();
        if d.is_none() {
            let shm = Path::new("/dev/shm");
            let b = tempfile::Builder::new().prefix("mint-fuzz").tempdir_in(if shm.is_dir() { shm.to_path_buf() } else { std::env::temp_dir() });
            *d = Some(b.or_else(|_| tempfile::Builder::new().prefix("mint-fuzz").tempdir()).expect("a scratch directory"));
        }
        d.as_ref().unwrap().path().to_path_buf()
    })
}

/// Writes `data` to `input.EXT` in the scratch directory.
fn input_file(ext: &str, data: &[u8]) -> PathBuf {
    let p = scratch().join(format!("input.{ext}"));
    std::fs::write(&p, data).expect("write the fuzz input");
    p
}

/// The error contract: one non-empty line that names the file.
fn one_line_naming(e: &dyn std::fmt::Display, path: &Path) {
    let s = e.to_string();
    assert!(!s.trim().is_empty(), "empty error message");
    assert!(!s.contains('\n') && !s.contains('\r'), "error of more than one line: {s:?}");
    let name = path.file_name().unwrap().to_str().unwrap();
    assert!(s.contains(name), "error does not name the file {name}: {s:?}");
}

// ---------------------------------------------------------------- readers

/// Mesh readers through `mint_io::MeshReader`: open, stream every chunk
/// (positions resolved), then `read_info`.
fn mesh_reader(ext: &str, data: &[u8]) {
    mesh_reader_at(&input_file(ext, data));
}

/// [`mesh_reader`] on a file already written.
fn mesh_reader_at(path: &Path) {
    let path = path.to_path_buf();
    // Small chunks: the chunk boundaries are exercised too.
    let opts = mint_io::ReadOptions { chunk_triangles: 7, spill_dir: Some(scratch()), resolve_positions: true };
    match mint_io::MeshReader::open(&path, opts) {
        Err(e) => one_line_naming(&e, &path),
        Ok(mut r) => {
            let n = r.vertex_count();
            if let Some(c) = r.colours() {
                assert_eq!(c.count(), n, "colours for {} of {n} vertices", c.count());
                for i in 0..n {
                    let _ = c.get(i);
                }
            }
            if let Some(g) = r.range_grid() {
                assert_eq!(g.cells.len() as u64, g.cols as u64 * g.rows as u64, "range grid of {}x{} with {} cells", g.cols, g.rows, g.cells.len());
                for c in g.cells.iter().flatten() {
                    assert!(*c < n, "range grid cell names vertex {c} of {n}");
                }
            }
            let mut chunk = mint_io::TriangleChunk::new();
            let mut total = 0u64;
            let mut streamed: Vec<[u32; 3]> = Vec::new();
            let mut stream_ok = true;
            // Fixed-size records (binary PLY, binary STL, a plain GLB) are
            // also read directly by the engine: both ways must agree.
            let records = r.triangle_records();
            loop {
                match r.next_chunk(&mut chunk) {
                    Err(e) => {
                        one_line_naming(&e, &path);
                        stream_ok = false;
                        break;
                    }
                    Ok(false) => {
                        assert!(chunk.is_empty(), "next_chunk gave false with a non-empty chunk");
                        break;
                    }
                    Ok(true) => {
                        assert!(chunk.len() <= 7, "chunk of {} triangles, asked for 7", chunk.len());
                        assert_eq!(chunk.indices.len(), chunk.positions.len());
                        for (t, p) in chunk.indices.iter().zip(&chunk.positions) {
                            for k in 0..3 {
                                assert!(t[k] < n, "triangle {t:?} names a vertex beyond {n}");
                                let v = r.vertex(t[k]);
                                assert!(p[k].iter().all(|c| c.is_finite()), "non-finite resolved position {:?}", p[k]);
                                assert_eq!(v.map(f64::to_bits), p[k].map(f64::to_bits), "resolved position differs from vertex({})", t[k]);
                            }
                        }
                        streamed.extend_from_slice(&chunk.indices);
                        total += chunk.len() as u64;
                    }
                }
            }
            // Face colours: one per triangle of the (first) face element.
            if let (Some(fc), true) = (r.face_colours(), stream_ok) {
                assert!(r.colours().is_none(), "vertex and face colours both given");
                assert!(fc.count() <= total, "{} face colours for {total} triangles", fc.count());
                for t in 0..fc.count() {
                    let _ = fc.get(t);
                }
            }
            // Textures: one record per triangle; decoded (when small) or
            // refused in one line; any triangle's colour is defined.
            if let Some(t) = r.texturing() {
                assert!(r.colours().is_none() && r.face_colours().is_none(), "texturing beside other colours");
                if stream_ok {
                    assert_eq!(t.triangles(), total, "texture records for {} of {total} triangles", t.triangles());
                }
                if t.decoded_bytes() <= 64 << 20 {
                    match t.decode(&path) {
                        Err(e) => one_line_naming(&e, &path),
                        Ok(images) => {
                            for k in 0..t.triangles().min(64) + 1 {
                                let _ = t.colour(&images, k, [0.2, 0.3, 0.5]);
                            }
                        }
                    }
                }
            }
            match records {
                Err(e) => one_line_naming(&e, &path),
                Ok(None) => {}
                Ok(Some(rec)) => {
                    let mut direct: Vec<[u32; 3]> = Vec::new();
                    match rec.visit_indices(0, rec.len(), |_, t| direct.push(t)) {
                        Err(e) => {
                            one_line_naming(&e, &path);
                            assert!(!stream_ok || r.info().format == mint_io::Format::Ply, "the records fail where the stream read every triangle: {e}");
                        }
                        Ok(()) => {
                            for t in &direct {
                                assert!(t.iter().all(|&v| v < n), "a record names a vertex beyond {n}: {t:?}");
                            }
                            if stream_ok {
                                assert_eq!(direct, streamed, "the records and the stream give other triangles");
                            }
                        }
                    }
                }
            }
            let _ = r.stats();
            let _ = r.warnings();
            assert!(total <= r.stats().triangles);
        }
    }
    match mint_io::read_info(&path) {
        Err(e) => one_line_naming(&e, &path),
        Ok(info) => assert_eq!(Some(info.format), mint_io::Format::from_extension(&path)),
    }
    check_against_in_core(&path);
}

/// `mint check` within a budget (`check_file`, spilling from the first
/// record, two threads) against the in-core check of the same file read
/// whole and welded: the same report wherever the in-core one succeeds;
/// otherwise a one-line error or a report.
fn check_against_in_core(path: &Path) {
    let opts = mint_check::CheckOptions { mem_bytes: 1, weld: true, tmp_dir: Some(scratch()), threads: 2, list_boundary: 0 };
    let bounded = mint_check::check_file(path, &opts, &mint_pipeline::NoProgress);
    let whole = mint_io::read_mesh(path).ok().and_then(|(mut p, mut f)| {
        let welded = mint_mesh::weld(&mut p, &mut f);
        let mut r = mint_mesh::try_check(&p, &f).ok()?;
        r.welded_vertices = welded;
        Some(r)
    });
    match (bounded, whole) {
        (Ok((got, _)), Some(want)) => assert!(reports_equal(&got, &want), "bounded check {got:?}\nin core {want:?}"),
        (Err(e), Some(_)) => panic!("the bounded check failed where the in-core one did not: {e}"),
        (Err(e), None) => one_line_naming(&e, path),
        (Ok(_), None) => {}
    }
}

/// Reports equal field for field, NaN sums (non-finite input) equal to NaN.
fn reports_equal(a: &mint_mesh::CheckReport, b: &mint_mesh::CheckReport) -> bool {
    let same = |x: f64, y: f64| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
    let (mut a2, mut b2) = (a.clone(), b.clone());
    let sums = same(a.signed_volume, b.signed_volume) && same(a.surface_area, b.surface_area);
    (a2.signed_volume, a2.surface_area, b2.signed_volume, b2.surface_area) = (0.0, 0.0, 0.0, 0.0);
    sums && a2 == b2
}

/// PLY: ascii, binary (both endians), faces, tristrips, range grids.
pub fn read_ply(data: &[u8]) {
    mesh_reader("ply", data)
}
/// Wavefront OBJ.
pub fn read_obj(data: &[u8]) {
    mesh_reader("obj", data)
}
/// STL, ascii and binary.
pub fn read_stl(data: &[u8]) {
    mesh_reader("stl", data)
}
/// OFF.
pub fn read_off(data: &[u8]) {
    mesh_reader("off", data)
}
/// The `.mesh` text format.
pub fn read_mesh(data: &[u8]) {
    mesh_reader("mesh", data)
}
/// Raw triangles.
pub fn read_raw(data: &[u8]) {
    mesh_reader("raw", data)
}
/// VRML 2.0.
pub fn read_wrl(data: &[u8]) {
    mesh_reader("wrl", data)
}
/// Binary glTF (GLB): the container's chunks, the JSON, accessors, views,
/// node transforms. When the JSON chunk parses, eight edits of its values
/// (seeded by the input) are read too, the BIN chunk kept: byte mutations
/// alone rarely leave JSON valid.
pub fn read_glb(data: &[u8]) {
    mesh_reader("glb", data);
    if data.len() >= 20 && &data[..4] == b"glTF" {
        let jl = u32::from_le_bytes(data[12..16].try_into().unwrap()) as usize;
        let Some(json) = data.get(20..20 + jl) else { return };
        let rest = &data[20 + jl..];
        for edited in gltf_edits(json) {
            mesh_reader("glb", &glb_of(edited, rest));
        }
    }
}
/// 3D Tiles: a tileset JSON (with eight edits of its values, as for
/// [`read_glb`]) or, when the input starts with `b3dm`, a lone b3dm tile.
/// Beside the input lie tiles a seed may name: `t.glb` (a tetrahedron),
/// `t.b3dm` (the same with an RTC_CENTER), `sub.json` (an external tileset
/// of `t.glb`) and `cut.glb` (a GLB cut short); the input itself is
/// `input.json`, so a seed naming it makes a cycle.
pub fn read_tileset(data: &[u8]) {
    // Its own directory: the tiles stay there between inputs.
    let dir = scratch().join("tileset");
    std::fs::create_dir_all(&dir).expect("a directory for the fuzz tiles");
    let tetra = tetra_glb();
    for (name, bytes) in [
        ("t.glb", tetra.clone()),
        ("t.b3dm", b3dm_of(&tetra)),
        ("sub.json", br#"{"asset":{"version":"1.1"},"root":{"geometricError":0,"contents":[{"uri":"t.glb"}]}}"#.to_vec()),
        ("cut.glb", tetra[..tetra.len() / 2].to_vec()),
    ] {
        if !dir.join(name).exists() {
            std::fs::write(dir.join(name), bytes).expect("write a fuzz tile");
        }
    }
    let read = |ext: &str, bytes: &[u8]| {
        let p = dir.join(format!("input.{ext}"));
        std::fs::write(&p, bytes).expect("write the fuzz input");
        mesh_reader_at(&p);
    };
    if data.starts_with(b"b3dm") {
        read("b3dm", data);
        return;
    }
    read("json", data);
    for edited in gltf_edits(data) {
        read("json", &edited);
    }
}

/// A GLB of one tetrahedron (f32 positions, u16 indices).
fn tetra_glb() -> Vec<u8> {
    let mut bin = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    for i in [0u16, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    let json = br#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],"buffers":[{"byteLength":72}],"bufferViews":[{"buffer":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":24}],"accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"},{"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}]}"#.to_vec();
    let mut chunk = (bin.len() as u32).to_le_bytes().to_vec();
    chunk.extend(0x004E_4942u32.to_le_bytes());
    chunk.extend(bin);
    glb_of(json, &chunk)
}

/// A GLB of the JSON chunk `json` (padded with spaces) followed by the
/// bytes `rest` (the BIN chunk with its header, or anything).
fn glb_of(mut json: Vec<u8>, rest: &[u8]) -> Vec<u8> {
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((20 + json.len() + rest.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(json);
    out.extend(rest);
    out
}

/// A b3dm holding `glb`, with an RTC_CENTER.
pub fn b3dm_of(glb: &[u8]) -> Vec<u8> {
    let table = br#"{"BATCH_LENGTH":0,"RTC_CENTER":[100.5,-200.25,6378137.0]}  "#;
    let mut out = b"b3dm".to_vec();
    for v in [1u32, (28 + table.len() + glb.len()) as u32, table.len() as u32, 0, 0, 0] {
        out.extend(v.to_le_bytes());
    }
    out.extend(table);
    out.extend(glb);
    out
}

/// glTF JSON (buffers as data URIs, or files that are missing), and eight
/// edits of its values as for [`read_glb`].
pub fn read_gltf(data: &[u8]) {
    mesh_reader("gltf", data);
    for edited in gltf_edits(data) {
        mesh_reader("gltf", &edited);
    }
}

/// Eight copies of the JSON `data`, each with one value replaced by a
/// boundary value (counts, offsets, indices, strides, types, transforms),
/// or an array element removed or duplicated; none when it does not parse.
fn gltf_edits(data: &[u8]) -> Vec<Vec<u8>> {
    let Ok(doc) = serde_json::from_slice::<serde_json::Value>(data) else { return Vec::new() };
    // Every value's path, in document order.
    fn paths(v: &serde_json::Value, at: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
        out.push(at.clone());
        match v {
            serde_json::Value::Object(m) => {
                for (k, x) in m {
                    at.push(k.clone());
                    paths(x, at, out);
                    at.pop();
                }
            }
            serde_json::Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    at.push(i.to_string());
                    paths(x, at, out);
                    at.pop();
                }
            }
            _ => {}
        }
    }
    let mut all = Vec::new();
    paths(&doc, &mut Vec::new(), &mut all);
    let values = [
        serde_json::json!(0), serde_json::json!(1), serde_json::json!(-1), serde_json::json!(3), serde_json::json!(4294967295u64),
        serde_json::json!(1e300), serde_json::json!(-0.5), serde_json::json!("VEC2"), serde_json::json!(5121), serde_json::json!(null),
        serde_json::json!([]), serde_json::json!({}), serde_json::json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1e308, 0, 0, 1]),
    ];
    let mut rng = mutate::Rng(crc32fast::hash(data) as u64);
    let mut out = Vec::new();
    for _ in 0..8 {
        let path = &all[rng.below(all.len())];
        let mut d = doc.clone();
        let mut v = &mut d;
        for k in path {
            v = match v {
                serde_json::Value::Object(m) => m.get_mut(k).unwrap(),
                serde_json::Value::Array(a) => &mut a[k.parse::<usize>().unwrap()],
                _ => unreachable!(),
            };
        }
        match (rng.below(4), &mut *v) {
            (0, serde_json::Value::Array(a)) if !a.is_empty() => {
                let i = rng.below(a.len());
                a.remove(i);
            }
            (1, serde_json::Value::Array(a)) if !a.is_empty() => {
                let i = rng.below(a.len());
                let x = a[i].clone();
                a.push(x);
            }
            _ => *v = values[rng.below(values.len())].clone(),
        }
        out.push(serde_json::to_vec(&d).unwrap());
    }
    out
}
/// An input list (`@list`, `mint_io::expand_inputs`) beside a folder
/// `input.t` holding `a.ply`, `b.obj`, `notes.txt` and `sub/c.stl`: every file it
/// gives exists, none twice; a refusal is one line naming the list (or,
/// for a file named twice, that file).
pub fn read_list(data: &[u8]) {
    let dir = scratch();
    let t = dir.join("input.t");
    if !t.is_dir() {
        std::fs::create_dir_all(t.join("sub")).expect("fixture folder");
        for f in ["a.ply", "b.obj", "notes.txt", "sub/c.stl"] {
            std::fs::write(t.join(f), b"x").expect("fixture file");
        }
    }
    let list = input_file("txt", data);
    match mint_io::expand_inputs(&[PathBuf::from(format!("@{}", list.display()))]) {
        Err(e) => {
            let s = e.to_string();
            if s.contains("named twice") {
                assert!(!s.contains('\n') && !s.contains('\r'), "error of more than one line: {s:?}");
            } else {
                one_line_naming(&e, &list);
            }
        }
        Ok(files) => {
            assert!(!files.is_empty());
            for f in &files {
                assert!(f.is_file(), "the list gave {}, which is not a file", f.display());
            }
            let mut c: Vec<PathBuf> = files.iter().map(|f| std::fs::canonicalize(f).unwrap()).collect();
            c.sort();
            assert!(c.windows(2).all(|w| w[0] != w[1]), "a file given twice: {files:?}");
        }
    }
}
/// 3D Studio.
pub fn read_3ds(data: &[u8]) {
    mesh_reader("3ds", data)
}

/// Contour profiles (`.pro`, mint-contour), streamed section by section.
pub fn read_pro(data: &[u8]) {
    use mint_contour::profile::{ProfileOptions, ProfileReader};
    let path = Path::new("input.pro");
    let mut r = ProfileReader::new(data, path, ProfileOptions::default());
    let mut last: Option<f64> = None;
    let mut n = 0usize;
    loop {
        match r.next_section() {
            Err(e) => {
                one_line_naming(&e, path);
                break;
            }
            Ok(None) => break,
            Ok(Some(s)) => {
                assert_eq!(s.index, n, "section index");
                n += 1;
                assert!(s.offset.is_finite(), "section offset {}", s.offset);
                if let Some(l) = last {
                    assert!(s.offset > l, "sections not in increasing order: {l} then {}", s.offset);
                }
                last = Some(s.offset);
                for c in &s.contours {
                    assert_eq!(c.points.len(), c.uv.len());
                    assert!(c.points.len() >= 3, "a contour of {} points", c.points.len());
                    assert!(c.points.iter().flatten().all(|x| x.is_finite()));
                    assert!(c.uv.iter().flatten().all(|x| x.is_finite()));
                }
            }
        }
    }
    if n > 0 {
        assert!(r.frame().is_some(), "sections read but no stack frame");
    }
}

fn scan_set(ext: &str, data: &[u8]) {
    let path = input_file(ext, data);
    match mint_range::ScanSet::read(&path) {
        Err(e) => one_line_naming(&e, &path),
        Ok(set) => {
            assert!(!set.entries.is_empty(), "a set with no scans");
            for e in &set.entries {
                let p = &e.pose;
                assert!(p.r.iter().flatten().chain(&p.t).all(|x| x.is_finite()), "non-finite pose of {}: {p:?}", e.file);
                assert!(p.orthogonality_error() < 1e-6, "pose of {} not orthonormal: {p:?}", e.file);
            }
            // The text written back reads back to the same scans.
            let format = mint_range::SetFormat::from_path(&path);
            let again = scratch().join(format!("again.{ext}"));
            std::fs::write(&again, set.to_text(format)).unwrap();
            let back = mint_range::ScanSet::read(&again).unwrap_or_else(|e| panic!("the written set does not read back: {e}"));
            assert_eq!(back.entries.len(), set.entries.len(), "scans written and read back");
        }
    }
}

/// Scan sets, `.conf`.
pub fn read_conf(data: &[u8]) {
    scan_set("conf", data)
}
/// Scan sets, `.aln`.
pub fn read_aln(data: &[u8]) {
    scan_set("aln", data)
}

/// `.rgrid` depth grids (mint-range), then triangulated.
pub fn read_rgrid(data: &[u8]) {
    let path = input_file("rgrid", data);
    match mint_range::depth_grid::read_depth_grid(&path) {
        Err(e) => one_line_naming(&e, &path),
        Ok(im) => {
            assert_eq!(im.cells.len() as u64, im.cols as u64 * im.rows as u64, "{}x{} grid with {} cells", im.cols, im.rows, im.cells.len());
            let n = im.points.len();
            for c in im.cells.iter().flatten() {
                assert!((*c as usize) < n, "cell names point {c} of {n}");
            }
            assert!(im.points.iter().flatten().all(|x| x.is_finite()), "non-finite point");
            for t in im.triangulate(f64::INFINITY) {
                assert!(t.iter().all(|&i| (i as usize) < n), "triangle {t:?} beyond {n} points");
            }
        }
    }
}

/// CSG scenes, parsed (not evaluated).
pub fn parse_scene(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let path = Path::new("scene.json");
    match mint_pipeline::parse_scene(&text, path) {
        Err(e) => {
            one_line_naming(&e, path);
            assert!(e.line >= 1, "error at line {}", e.line);
        }
        Ok(s) => {
            assert!(!s.operands.is_empty(), "a scene without operands");
        }
    }
}

/// A staged run's `plan.json` (mint-pipeline's `Plan::parse`): as given,
/// and resealed (its checksum recomputed after the mutation, so that what
/// the plan claims is judged, not only its checksum). A refusal is one line
/// naming the file; an accepted plan's stages follow from its spec.
pub fn read_plan(data: &[u8]) {
    let path = Path::new("w/plan.json");
    let judge = |bytes: &[u8]| match mint_pipeline::Plan::parse(bytes, path) {
        Err(e) => one_line_naming(&e, path),
        Ok(p) => {
            assert!(p.parts >= 1 && p.slabs >= 1 && p.parts <= mint_pipeline::plan::MAX_TASKS && p.slabs <= mint_pipeline::plan::MAX_TASKS);
            assert!(p.stages.iter().all(|s| s.tasks <= mint_pipeline::plan::MAX_TASKS), "a stage of {:?} tasks", p.stages);
        }
    };
    judge(data);
    if let Ok(mut v) = serde_json::from_slice::<serde_json::Value>(data) {
        if v.is_object() {
            mint_pipeline::plan::seal(&mut v);
            judge(serde_json::to_string(&v).unwrap().as_bytes());
        }
    }
}

// ------------------------------------------------------- work directories

/// The stage template: a finished staged run (a UV sphere, 2 parts, 2
/// slabs, hole closing on) in this thread's scratch directory, made once.
/// Returns (input, output, work directory, spec, tuning).
fn stage_template() -> (PathBuf, PathBuf, PathBuf, mint_pipeline::RunSpec, mint_pipeline::Tuning) {
    use mint_core::sink::MeshSink;
    let root = scratch().join("stage-template");
    let (input, output, work) = (root.join("in.ply"), root.join("out.ply"), root.join("w"));
    let spec = mint_pipeline::RunSpec::resample(&input, &output, mint_core::GridSize::Cells(3000));
    let tuning = mint_pipeline::Tuning { threads: 1, mem_bytes: 64 << 20, parts: 2, slabs: 2, work_dir: Some(work.clone()), tmp_dir: Some(root.clone()), ..Default::default() };
    if !root.join("done").exists() {
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&root).unwrap();
        let (n_lat, n_lon) = (12usize, 16usize);
        let mut w = mint_io::MeshWriter::create(&input, mint_io::Format::Ply, Default::default()).unwrap();
        let at = |i: usize, j: usize| {
            let (th, ph) = (std::f64::consts::PI * i as f64 / n_lat as f64, 2.0 * std::f64::consts::PI * j as f64 / n_lon as f64);
            [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()]
        };
        // Poles once, rings between.
        let id = |i: usize, j: usize| -> u32 {
            if i == 0 { 0 } else if i == n_lat { 1 + ((n_lat - 1) * n_lon) as u32 } else { (1 + (i - 1) * n_lon + j % n_lon) as u32 }
        };
        w.vertex(at(0, 0)).unwrap();
        for i in 1..n_lat {
            for j in 0..n_lon {
                w.vertex(at(i, j)).unwrap();
            }
        }
        w.vertex(at(n_lat, 0)).unwrap();
        for i in 0..n_lat {
            for j in 0..n_lon {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if i != 0 {
                    w.face([a, b, d]).unwrap();
                }
                if i != n_lat - 1 {
                    w.face([b, c, d]).unwrap();
                }
            }
        }
        w.finish().unwrap();
        mint_pipeline::run(&spec, &tuning, &mint_pipeline::NoProgress).expect("the stage template runs");
        std::fs::write(root.join("done"), b"").unwrap();
    }
    (input, output, work, spec, tuning)
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if e.file_type().unwrap().is_dir() {
            copy_dir(&src, &dst);
        } else {
            std::fs::copy(&src, &dst).unwrap();
        }
    }
}

/// Files under `dir`, relative, sorted.
fn files_under(dir: &Path, rel: &Path, out: &mut Vec<PathBuf>) {
    let mut es: Vec<_> = std::fs::read_dir(dir.join(rel)).unwrap().flatten().collect();
    es.sort_by_key(|e| e.file_name());
    for e in es {
        let r = rel.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            files_under(dir, &r, out);
        } else {
            out.push(r);
        }
    }
}

/// Writes a task result's body with its checksum line recomputed.
fn reseal_result(path: &Path, bytes: &[u8]) {
    let body = match bytes.strip_prefix(b"crc32 ") {
        Some(rest) => rest.iter().position(|&b| b == b'\n').map_or(&b""[..], |nl| &rest[nl + 1..]),
        None => bytes,
    };
    let body = body.strip_suffix(b"\n").unwrap_or(body);
    let mut out = format!("crc32 {:08x}\n", crc32fast::hash(body)).into_bytes();
    out.extend_from_slice(body);
    out.push(b'\n');
    std::fs::write(path, out).unwrap();
}

/// Replaces, anywhere in `v`, an object's `{len: old.0, crc32: old.1}` by `new`.
fn replace_sum(v: &mut serde_json::Value, old: (u64, u32), new: (u64, u32)) {
    match v {
        serde_json::Value::Object(m) => {
            if m.get("len").and_then(|x| x.as_u64()) == Some(old.0) && m.get("crc32").and_then(|x| x.as_u64()) == Some(old.1 as u64) {
                m.insert("len".into(), new.0.into());
                m.insert("crc32".into(), new.1.into());
            }
            for x in m.values_mut() {
                replace_sum(x, old, new);
            }
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(|x| replace_sum(x, old, new)),
        _ => {}
    }
}

/// Numbers a JSON edit puts in place of another.
const EDGE_NUMBERS: [f64; 12] = [0.0, -1.0, 1.0, 2.0, 65536.0, 4294967295.0, 4294967296.0, 9007199254740993.0, 1e308, -1e308, 0.5, 1e-300];

/// The `k`-th number leaf of `v` (in document order), replaced by `x`.
fn edit_number(v: &mut serde_json::Value, k: &mut usize, x: f64) -> bool {
    match v {
        serde_json::Value::Number(_) => {
            if *k == 0 {
                *v = if x.fract() == 0.0 && x >= 0.0 && x < 1.8e19 { (x as u64).into() } else if x.fract() == 0.0 && x > -9.2e18 && x < 0.0 { (x as i64).into() } else { serde_json::Number::from_f64(x).map_or(serde_json::Value::Null, serde_json::Value::Number) };
                return true;
            }
            *k -= 1;
            false
        }
        serde_json::Value::Object(m) => m.values_mut().any(|x2| edit_number(x2, k, x)),
        serde_json::Value::Array(a) => a.iter_mut().any(|x2| edit_number(x2, k, x)),
        _ => false,
    }
}

/// Work directories turned against mint (issue 26): a small finished staged
/// run's files (plan, task results, shards, slab files); byte 0 picks one,
/// byte 1 the edit (0: bytes overwritten at the positions the rest gives;
/// 1: truncated; 2: replaced by the rest; 3: a number of the JSON set to
/// an edge value), and every checksum that guards it is recomputed: a
/// result's own line, the `{len, crc32}` of a data file in the result that
/// lists it, the plan's seal. Later stages' tasks and the output are
/// removed and the run resumed. It must end `Ok` with a readable output, or
/// with one line naming a file; it must never panic, hang or index past a
/// table. (Checksums catch accidents; what a file claims must be checked.)
pub fn stage(data: &[u8]) {
    if data.len() < 2 {
        return;
    }
    let (input, output, template, spec, tuning) = stage_template();
    let work = scratch().join("stage-w");
    let _ = std::fs::remove_dir_all(&work);
    copy_dir(&template, &work);
    let mut files = Vec::new();
    files_under(&work, Path::new(""), &mut files);
    let rel = files[data[0] as usize % files.len()].clone();
    let path = work.join(&rel);
    let old = std::fs::read(&path).unwrap();
    let rest = &data[2..];
    let new: Vec<u8> = match data[1] % 4 {
        0 => {
            let mut b = old.clone();
            for e in rest.chunks_exact(3) {
                if !b.is_empty() {
                    let at = u16::from_le_bytes([e[0], e[1]]) as usize % b.len();
                    b[at] = e[2];
                }
            }
            b
        }
        1 => {
            let n = rest.first().map_or(0, |&x| x as usize) * old.len() / 256;
            old[..n].to_vec()
        }
        2 => rest.to_vec(),
        _ => {
            let body = if old.starts_with(b"crc32 ") { &old[old.iter().position(|&b| b == b'\n').map_or(old.len(), |n| n + 1)..] } else { &old[..] };
            let Ok(mut v) = serde_json::from_slice::<serde_json::Value>(body) else { return };
            let mut k = rest.first().map_or(0, |&x| x as usize);
            let x = EDGE_NUMBERS[rest.get(1).map_or(0, |&x| x as usize) % EDGE_NUMBERS.len()];
            if !edit_number(&mut v, &mut k, x) {
                return;
            }
            serde_json::to_string_pretty(&v).unwrap().into_bytes()
        }
    };
    let name = rel.file_name().unwrap().to_string_lossy().into_owned();
    if name == "plan.json" {
        match serde_json::from_slice::<serde_json::Value>(&new) {
            Ok(mut v) if v.is_object() => {
                mint_pipeline::plan::seal(&mut v);
                std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
            }
            _ => std::fs::write(&path, &new).unwrap(),
        }
    } else if name == "result.json" {
        reseal_result(&path, &new);
    } else {
        std::fs::write(&path, &new).unwrap();
        // The result that lists this data file: in its task directory.
        let mut dir = path.parent().unwrap().to_path_buf();
        while !dir.join("result.json").is_file() && dir.starts_with(&work) && dir != work {
            dir = dir.parent().unwrap().to_path_buf();
        }
        let result = dir.join("result.json");
        if result.is_file() {
            let text = std::fs::read(&result).unwrap();
            let nl = text.iter().position(|&b| b == b'\n').unwrap();
            let mut v: serde_json::Value = serde_json::from_slice(&text[nl + 1..]).unwrap();
            replace_sum(&mut v, (old.len() as u64, crc32fast::hash(&old)), (new.len() as u64, crc32fast::hash(&new)));
            reseal_result(&result, serde_json::to_string_pretty(&v).unwrap().as_bytes());
        }
    }
    // Later stages run again (and the output is written again).
    let order = ["bounds", "discretize", "census", "reconstruct", "reopen", "write"];
    let first = rel.components().next().unwrap().as_os_str().to_string_lossy().into_owned();
    if let Some(i) = order.iter().position(|s| *s == first) {
        for later in &order[i + 1..] {
            let _ = std::fs::remove_dir_all(work.join(later));
        }
    } else {
        // plan.json: every task's result stays; the plan decides.
    }
    // The copy describes the template's run: the same input and output.
    let out = output;
    let _ = std::fs::remove_file(&out);
    let tuning = mint_pipeline::Tuning { work_dir: Some(work.clone()), ..tuning };
    let r = mint_pipeline::run(&spec, &tuning, &mint_pipeline::NoProgress);
    match r {
        Err(e) => {
            let s = e.to_string();
            assert!(!s.trim().is_empty() && !s.contains('\n'), "error not one line: {s:?}");
            let names_one = [&work, &out, &input].iter().any(|p| s.contains(&*p.to_string_lossy()) || s.contains(&*p.file_name().unwrap().to_string_lossy()));
            assert!(names_one, "error names no file of the run: {s:?}");
            assert!(!out.exists(), "an error left the output behind: {s}");
        }
        Ok(_) => {
            mint_io::read_mesh(&out).expect("a finished run's output reads back");
        }
    }
}

// ------------------------------------------------------------- geometry

/// A coordinate on the lattice of multiples of 0.5 in [-4, 4] (17 values).
fn lattice(b: u8) -> f64 {
    (b % 17) as f64 * 0.5 - 4.0
}

/// `mint_core::discretize_triangle` on tetrahedra with vertices on a small
/// lattice of half cells, where ties with grid lines and nodes are the
/// rule. Every 12 bytes are one tetrahedron. Checks each crossing (family,
/// value inside its cell by the margin, line and cell within the triangle's
/// box, one crossing per line, one sign per family) and, for the closed
/// tetrahedron, that every grid line crosses it 0 or 2 times, once in and
/// once out, in this order along the line (outward faces), at the same cell
/// when it is flat.
pub fn discretize(data: &[u8]) {
    use mint_core::{discretize_triangle, Crossing, MARGIN};
    use std::collections::BTreeMap;
    for bytes in data.chunks_exact(12).take(8) {
        let p: Vec<[f64; 3]> = bytes.chunks_exact(3).map(|c| [lattice(c[0]), lattice(c[1]), lattice(c[2])]).collect();
        let (a, b, c, d) = (p[0], p[1], p[2], p[3]);
        let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
        let (u, v, w) = (sub(b, a), sub(c, a), sub(d, a));
        // Exact: half-integers below 8 in magnitude.
        let det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
        // Consistently oriented; inward when det > 0.
        let faces = [[a, b, c], [a, c, d], [a, d, b], [b, d, c]];
        let mut lines: BTreeMap<(u8, i64, i64), Vec<Crossing>> = BTreeMap::new();
        for t in &faces {
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for q in t {
                for k in 0..3 {
                    lo[k] = lo[k].min(q[k]);
                    hi[k] = hi[k].max(q[k]);
                }
            }
            let mut mine: Vec<Crossing> = Vec::new();
            discretize_triangle(t, |x| mine.push(x));
            for x in &mine {
                let f = x.family as usize;
                assert!(f < 3, "family {f}");
                let (du, dv) = ((f + 1) % 3, (f + 2) % 3);
                let cell = x.cell as f64;
                assert!(x.value.is_finite() && x.value >= cell + MARGIN && x.value <= cell + 1.0 - MARGIN, "{t:?}: value {} outside cell {} by the margin", x.value, x.cell);
                assert!(x.u as f64 >= lo[du].floor() && x.u as f64 <= hi[du].ceil(), "{t:?}: line u = {} outside the triangle's box", x.u);
                assert!(x.v as f64 >= lo[dv].floor() && x.v as f64 <= hi[dv].ceil(), "{t:?}: line v = {} outside the triangle's box", x.v);
                assert!(cell >= lo[f].floor() - 1.0 && cell <= hi[f].ceil(), "{t:?}: cell {} outside the triangle's box along {f}", x.cell);
                assert!(mine.iter().filter(|y| (y.family, y.u, y.v) == (x.family, x.u, x.v)).count() == 1, "{t:?}: line {:?} crossed twice", (x.family, x.u, x.v));
                assert!(mine.iter().all(|y| y.family != x.family || y.entering == x.entering), "{t:?}: two signs on family {f}");
                lines.entry((x.family, x.u, x.v)).or_default().push(*x);
            }
        }
        for (line, xs) in &lines {
            let ins: Vec<&Crossing> = xs.iter().filter(|x| x.entering).collect();
            let outs: Vec<&Crossing> = xs.iter().filter(|x| !x.entering).collect();
            assert!(ins.len() == outs.len(), "tetrahedron {p:?} (det {det}): line {line:?} crossed {} times in, {} out", ins.len(), outs.len());
            if det != 0.0 {
                assert!(xs.len() == 2, "convex tetrahedron {p:?}: line {line:?} crossed {} times", xs.len());
                let (i, o) = (ins[0].cell, outs[0].cell);
                // Outward faces (det < 0): in, then out, walking towards +family.
                let ok = if det < 0.0 { i <= o } else { o <= i };
                assert!(ok, "tetrahedron {p:?} (det {det}): line {line:?} enters at cell {i}, leaves at cell {o}");
            } else {
                assert!(xs.iter().all(|x| x.cell == xs[0].cell), "flat tetrahedron {p:?}: line {line:?} crossed at cells {:?}", xs.iter().map(|x| x.cell).collect::<Vec<_>>());
            }
        }
    }
}

/// A small resampling (`mint_pipeline::resample`, one thread, a few hundred
/// cells) of a tiny mesh built from the bytes (vertices on a lattice of
/// half units, faces by index): byte 0 picks the sign rule and the cell
/// count, byte 1 the number of vertices, then 3 bytes per vertex and 3 per
/// face. The output's faces name existing vertices and never repeat one; under the
/// robust rules (Auto, Union, Parity; every hole closed) it is closed:
/// every edge on exactly two faces, in opposite directions, and manifold.
/// The same bytes come out with dereferencing by sort, and from the same
/// mesh written as binary PLY (the direct path over fixed-size records, on
/// an AVX2 CPU its vector compilation, against the text file's streamed
/// path). With bit 5 of byte 0 every vertex has a colour (its three bytes):
/// the output then carries colour, and the streamed and direct coloured
/// reads must agree byte for byte too.
pub fn resample(data: &[u8]) {
    use mint_core::signs::SignRule;
    if data.len() < 2 {
        return;
    }
    let rule = [SignRule::Auto, SignRule::Union, SignRule::Parity, SignRule::Orient][(data[0] & 3) as usize];
    let cells = 64 + 64 * u64::from(data[0] >> 2 & 7);
    let coloured = data[0] & 0x20 != 0;
    let colour_props = if coloured { "property uchar red\nproperty uchar green\nproperty uchar blue\n" } else { "" };
    let nv = (data[1] % 16) as usize + 3;
    let rest = &data[2..];
    if rest.len() < 3 * nv + 3 {
        return;
    }
    let (vb, fb) = rest.split_at(3 * nv);
    let faces: Vec<[usize; 3]> = fb.chunks_exact(3).take(64).map(|c| [c[0] as usize % nv, c[1] as usize % nv, c[2] as usize % nv]).collect();
    let mut ply = format!("ply\nformat ascii 1.0\nelement vertex {nv}\nproperty double x\nproperty double y\nproperty double z\n{colour_props}element face {}\nproperty list uchar int vertex_indices\nend_header\n", faces.len());
    for c in vb.chunks_exact(3) {
        ply += &format!("{} {} {}", lattice(c[0]), lattice(c[1]), lattice(c[2]));
        if coloured {
            ply += &format!(" {} {} {}", c[0], c[1], c[2]);
        }
        ply += "\n";
    }
    for f in &faces {
        ply += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    let input = input_file("ply", ply.as_bytes());
    let output = scratch().join("out.ply");
    let _ = std::fs::remove_file(&output);
    let spec_of = |input: &std::path::Path, output: &std::path::Path| {
        let mut s = mint_pipeline::RunSpec::resample(input, output, mint_core::GridSize::Cells(cells));
        s.signs = rule;
        s.max_hole = None;
        s
    };
    let opts = mint_pipeline::Tuning { threads: 1, mem_bytes: 64 << 20, tmp_dir: Some(scratch()), ..Default::default() };
    match mint_pipeline::run(&spec_of(&input, &output), &opts, &mint_pipeline::NoProgress) {
        Err(e) => {
            let s = e.to_string();
            assert!(!s.trim().is_empty() && !s.contains('\n'), "error not one line: {s:?}");
            assert!(!output.exists(), "an error left the output behind: {s}");
        }
        Ok(_) => {
            // Dereferencing by sort gives the same bytes.
            let want = std::fs::read(&output).unwrap();
            let sorted = scratch().join("again.ply");
            let o = mint_pipeline::Tuning { deref: mint_pipeline::Deref::Sort, mem_bytes: 1, ..opts.clone() };
            mint_pipeline::run(&spec_of(&input, &sorted), &o, &mint_pipeline::NoProgress).unwrap_or_else(|e| panic!("--deref sort failed where mmap did not: {e}"));
            assert!(std::fs::read(&sorted).unwrap() == want, "--deref sort gives other bytes than mmap");
            // The same mesh as binary PLY: its fixed-size records take the
            // direct path (on this CPU perhaps its AVX2 compilation), the
            // text file the streamed one; the bytes must not differ.
            let mut bin = format!("ply\nformat binary_little_endian 1.0\nelement vertex {nv}\nproperty double x\nproperty double y\nproperty double z\n{colour_props}element face {}\nproperty list uchar int vertex_indices\nend_header\n", faces.len()).into_bytes();
            for c in vb.chunks_exact(3) {
                for &b in c {
                    bin.extend_from_slice(&lattice(b).to_le_bytes());
                }
                if coloured {
                    bin.extend_from_slice(c);
                }
            }
            for f in &faces {
                bin.push(3);
                for &v in f {
                    bin.extend_from_slice(&(v as i32).to_le_bytes());
                }
            }
            let binary = input_file("bin.ply", &bin);
            let direct = scratch().join("again.bin.ply");
            mint_pipeline::run(&spec_of(&binary, &direct), &opts, &mint_pipeline::NoProgress).unwrap_or_else(|e| panic!("the binary copy failed where the text file did not: {e}"));
            assert!(std::fs::read(&direct).unwrap() == want, "the binary copy (direct path) gives other bytes than the text file");
            let (pos, faces) = mint_io::read_mesh(&output).unwrap_or_else(|e| panic!("the output does not read back: {e}"));
            let out_colours = mint_io::MeshReader::open(&output, mint_io::ReadOptions::default()).unwrap().colours();
            // (An empty output has no colour to read back.)
            if !pos.is_empty() {
                assert_eq!(out_colours.is_some(), coloured, "coloured input {coloured}, coloured output {}", out_colours.is_some());
            }
            let rep = mint_mesh::try_check(&pos, &faces).unwrap_or_else(|e| panic!("output fails the index check: {e}"));
            assert_eq!(rep.collapsed_faces, 0, "output faces repeat a vertex");
            assert_eq!(rep.non_finite_vertices, 0, "non-finite output vertices");
            if rule != SignRule::Orient {
                assert!(
                    rep.boundary_edges == 0 && rep.non_manifold_edges == 0 && rep.inconsistently_oriented_edges == 0 && rep.non_manifold_vertices == 0,
                    "{rule:?}, {cells} cells: output not closed: {} boundary, {} non-manifold edges, {} misoriented edges, {} non-manifold vertices",
                    rep.boundary_edges,
                    rep.non_manifold_edges,
                    rep.inconsistently_oriented_edges,
                    rep.non_manifold_vertices
                );
            }
        }
    }
    // Nothing of the run is left in the scratch directory but our files.
    for e in std::fs::read_dir(scratch()).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        assert!(name.starts_with("input.") || name.starts_with("again.") || name.starts_with("stage-") || name == "out.ply" || name == "tileset", "the run left {name} behind");
    }
}

/// The in-core simplifier on small meshes over the half-cell lattice:
/// `data[0]` picks the target (low 4 bits: a fraction of the faces) and
/// the blocks (high bits: 1 to 4), `data[1]` the vertex count (low 5 bits)
/// and the quadrics' planes (bit 7: lifted, as for an intermediate), then
/// 3 bytes a vertex and 3 bytes a face. Checks that nothing panics, that indices
/// stay valid and positions finite, and that a closed, 2-manifold,
/// oriented input keeps that and its genera under `qem::collapse_in_blocks`
/// itself (not only under `simplify`, which may relax its target), and
/// that `simplify` hands over a watertight mesh whenever it got one.
pub fn simplify(data: &[u8]) {
    if data.len() < 2 {
        return;
    }
    let fraction = f64::from(data[0] & 15) / 15.0;
    let blocks = usize::from(data[0] >> 4) % 4 + 1;
    let nv = (data[1] % 32) as usize + 4;
    let planes = if data[1] & 0x80 != 0 { mint_mesh::qem::Planes::Lifted } else { mint_mesh::qem::Planes::Faces };
    let rest = &data[2..];
    if rest.len() < 3 * nv + 3 {
        return;
    }
    let (vb, fb) = rest.split_at(3 * nv);
    let positions: Vec<[f64; 3]> = vb.chunks_exact(3).map(|c| [lattice(c[0]), lattice(c[1]), lattice(c[2])]).collect();
    let faces: Vec<[u32; 3]> = fb.chunks_exact(3).take(96).map(|c| [0, 1, 2].map(|k| (c[k] as usize % nv) as u32)).collect();
    let before = mint_mesh::check(&positions, &faces);
    let target = (fraction * faces.len() as f64) as u64;
    // One thread: no spawned threads for the leak checker to trip on (the
    // thread count does not change the result: a unit test checks it).
    let (p, f, _) = mint_mesh::qem::collapse_in_blocks(&positions, &faces, planes, target, f64::INFINITY, blocks, 1, &|| false);
    assert!(f.len() <= faces.len(), "faces grew");
    assert!(f.iter().flatten().all(|&v| (v as usize) < p.len()), "an index out of range");
    assert!(f.iter().flatten().all(|&v| p[v as usize].iter().all(|c| c.is_finite())), "a non-finite position");
    if before.watertight {
        let after = mint_mesh::check(&p, &f);
        assert!(after.watertight, "{blocks} blocks, target {target}: a watertight input lost it: {after:?}");
        assert_eq!(after.genera, before.genera, "{blocks} blocks, target {target}: genera changed");
    }
    if target >= 4 {
        if let Ok((_, _, r)) = mint_mesh::simplify(&positions, &faces, &mint_mesh::SimplifyOptions { target_faces: target, max_error: 1.0, planes }) {
            assert!(!r.input_watertight || r.output_watertight, "simplify handed over a worse mesh: {r:?}");
        }
    }
    // The colour-aware collapse (each vertex coloured by its bytes): the
    // same checks, and every kept colour within the range of the input's.
    let colours: Vec<[u8; 4]> = vb.chunks_exact(3).map(|c| [c[0], c[1], c[2], 255]).collect();
    let (p, f, c, _) = mint_mesh::qem::collapse_coloured(&positions, &faces, planes, &colours, 0.01, target, f64::INFINITY, blocks, 1, &|| false);
    assert!(f.len() <= faces.len() && c.len() == p.len(), "faces grew, or colours for other vertices");
    assert!(f.iter().flatten().all(|&v| (v as usize) < p.len() && p[v as usize].iter().all(|x| x.is_finite())), "an index out of range or a non-finite position");
    for k in 0..3 {
        let (lo, hi) = (colours.iter().map(|x| x[k]).min().unwrap(), colours.iter().map(|x| x[k]).max().unwrap());
        assert!(f.iter().flatten().all(|&v| (lo..=hi).contains(&c[v as usize][k])), "a colour outside the input's range");
    }
    if before.watertight {
        let after = mint_mesh::check(&p, &f);
        assert!(after.watertight, "coloured, {blocks} blocks, target {target}: a watertight input lost it: {after:?}");
    }
}

// ---------------------------------------------------------------- volumes

/// The most samples a volume target reads (a header may claim any size).
const MAX_FUZZ_SAMPLES: u64 = 1 << 20;

/// Opens `path` as a volume and reads every slice when it is small: an
/// error keeps the contract, a volume reads as finite or NaN values.
fn volume_at(path: &Path) {
    match mint_volume::Volume::open(path, &mint_volume::OpenOptions::default()) {
        Err(e) => one_line_naming(&e, path),
        Ok(mut v) => {
            let info = v.info().clone();
            let n = info.slice_len() as u64;
            assert!(n > 0 && info.dims[2] > 0, "an open volume of {:?} samples", info.dims);
            if n * info.dims[2] <= MAX_FUZZ_SAMPLES {
                let mut s = vec![0f32; (n * info.dims[2]) as usize];
                match v.read_slices(0, info.dims[2], &mut s) {
                    Err(e) => {
                        let s = e.to_string();
                        assert!(!s.trim().is_empty() && !s.contains('\n'), "error of more than one line: {s:?}");
                    }
                    Ok(()) => assert!(s.iter().all(|x| !x.is_infinite() || info.sample.is_float()), "an integer volume read an infinity"),
                }
            }
        }
    }
}

/// NRRD headers (attached data after the blank line).
pub fn read_nrrd(data: &[u8]) {
    volume_at(&input_file("nrrd", data));
}

/// MetaImage headers (`.mha`, data `LOCAL` or named).
pub fn read_metaimage(data: &[u8]) {
    volume_at(&input_file("mha", data));
}

/// NIfTI-1 headers and data (`.nii`).
pub fn read_nifti(data: &[u8]) {
    volume_at(&input_file("nii", data));
}

/// A DICOM series of one file (a folder holding `data` as `1.dcm`).
pub fn read_dicom_volume(data: &[u8]) {
    let dir = scratch().join("dicom");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    let f = dir.join("1.dcm");
    std::fs::write(&f, data).expect("write the fuzz input");
    match mint_volume::Volume::open(&dir, &mint_volume::OpenOptions::default()) {
        Err(e) => {
            let s = e.to_string();
            assert!(!s.trim().is_empty() && !s.contains('\n'), "error of more than one line: {s:?}");
        }
        Ok(_) => volume_at(&dir),
    }
}

/// TIFF files (one or more pages).
pub fn read_tiff_volume(data: &[u8]) {
    volume_at(&input_file("tif", data));
}

/// A tiny volume from the bytes (dims 1..=5 each, u8 samples, an iso or a
/// label, the own grid or a coarser or finer one) through the engine's
/// core: crossings, then the robust reconstruction. The surface must be
/// closed, 2-manifold and oriented, whatever the samples.
pub fn volume(data: &[u8]) {
    use mint_core::grid::{Grid, GridSize};
    use mint_core::volume::{volume_planes, Field, Placement};
    if data.len() < 5 {
        return;
    }
    let dims = [0, 1, 2].map(|d| (data[d] % 5) as u64 + 1);
    let n = (dims[0] * dims[1] * dims[2]) as usize;
    let samples: Vec<f32> = (0..n).map(|i| data.get(5 + i).copied().unwrap_or(0) as f32).collect();
    let field = if data[3] & 1 == 0 { Field::Iso((data[3] >> 1) as f32 * 2.0) } else { Field::Label(((data[3] >> 1) % 4) as f32) };
    let cell = [1.0, 0.7, 1.6, 2.5][(data[4] & 3) as usize];
    let (lo, hi) = if cell == 1.0 { ([0.0; 3], dims.map(|n| (n - 1) as f64)) } else { ([-0.5; 3], dims.map(|n| n as f64 - 0.5)) };
    let g = Grid::around(lo, hi, GridSize::CellSize(cell), [0.0; 3], Some(2)).expect("a small grid");
    let [na, nb, ns] = g.local_dims();
    let p = Placement { axis: [0, 1, 2], start: g.origin, step: [cell; 3], dims, nodes: [na + 1, nb + 1, ns + 1] };
    let planes = volume_planes(&p, field, &samples);
    let (r, _) = mint_core::robust::reconstruct_slab_robust(&g, 0, planes, mint_core::signs::SignRule::Union);
    let c = mint_mesh::check(&r.vertices, &r.faces);
    assert_eq!((c.boundary_edges, c.non_manifold_edges, c.inconsistently_oriented_edges), (0, 0, 0), "dims {dims:?} {field:?} cell {cell}: {c:?}");
    assert!(c.signed_volume >= -1e-9, "inside out: {}", c.signed_volume);
}
