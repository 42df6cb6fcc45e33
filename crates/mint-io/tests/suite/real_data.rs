//! The real scans in shared/data (skipped with a message when the folder is
//! absent). Expected counts are those of each folder's PROVENANCE.md:
//! vertices and triangles for meshes (igea's strip expands to 268686
//! triangles with no degenerate ones), grid size for range scans (whose
//! filled cells equal the vertex count and which have no faces). Every .ply
//! file in the folder must be in the table and read completely.
use std::collections::HashSet;
use std::path::Path;

use mint_io::{convert, read_info, MeshReader, ReadOptions, TriangleChunk, WriteOptions};

use super::util::{as_f32, data_dir, read, read_all};

/// (path, vertices, triangles, Some((rows, cols)) for range scans).
type Expected = (&'static str, u64, u64, Option<(u32, u32)>);

const EXPECTED: &[Expected] = &[
    ("stanford_bunny_zipper_mesh/bun_zipper.ply", 35947, 69451, None),
    ("stanford_bunny_zipper_mesh/bun_zipper_res2.ply", 8171, 16301, None),
    ("stanford_bunny_zipper_mesh/bun_zipper_res3.ply", 1889, 3851, None),
    ("stanford_bunny_zipper_mesh/bun_zipper_res4.ply", 453, 948, None),
    ("cyberware_horse_mesh/horse.ply", 48485, 96966, None),
    ("cyberware_igea_mesh/igea.ply", 134345, 268686, None),
    ("stanford_bunny_range_scans/bun000.ply", 40256, 0, Some((400, 512))),
    ("stanford_bunny_range_scans/bun045.ply", 40097, 0, Some((400, 512))),
    ("stanford_bunny_range_scans/bun090.ply", 30379, 0, Some((400, 512))),
    ("stanford_bunny_range_scans/bun180.ply", 40251, 0, Some((400, 512))),
    ("stanford_bunny_range_scans/bun270.ply", 31701, 0, Some((400, 512))),
    ("stanford_bunny_range_scans/bun315.ply", 35336, 0, Some((400, 512))),
    ("stanford_bunny_range_scans/chin.ply", 37738, 0, Some((400, 512))),
    ("stanford_bunny_range_scans/ear_back.ply", 32193, 0, Some((400, 512))),
    ("stanford_bunny_range_scans/top2.ply", 38298, 0, Some((400, 512))),
    ("stanford_bunny_range_scans/top3.ply", 36023, 0, Some((400, 512))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_0.ply", 41841, 0, Some((262, 483))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_24.ply", 34836, 0, Some((264, 500))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_48.ply", 22092, 0, Some((268, 474))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_72.ply", 14879, 0, Some((272, 370))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_96.ply", 20645, 0, Some((272, 363))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_120.ply", 34436, 0, Some((272, 441))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_144.ply", 43181, 0, Some((268, 493))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_168.ply", 44329, 0, Some((264, 508))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_192.ply", 39526, 0, Some((266, 492))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_216.ply", 30492, 0, Some((278, 544))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_240.ply", 19318, 0, Some((272, 423))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_264.ply", 15050, 0, Some((280, 522))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_288.ply", 24573, 0, Some((276, 509))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_312.ply", 40528, 0, Some((272, 496))),
    ("stanford_dragon_stand_range_scans/dragonStandRight_336.ply", 43467, 0, Some((268, 497))),
];

fn ply_files(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for sub in std::fs::read_dir(dir).unwrap() {
        let sub = sub.unwrap().path();
        if sub.is_dir() {
            for f in std::fs::read_dir(&sub).unwrap() {
                let f = f.unwrap().path();
                if f.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply")) {
                    out.push(f.strip_prefix(dir).unwrap().to_string_lossy().replace('\\', "/"));
                }
            }
        }
    }
    out.sort();
    out
}

#[test]
fn every_real_ply_reads_completely_with_provenance_counts() {
    let Some(dir) = data_dir() else { return };
    let listed: HashSet<&str> = EXPECTED.iter().map(|e| e.0).collect();
    for f in ply_files(&dir) {
        assert!(listed.contains(f.as_str()), "{f} is not in the expected-counts table");
    }
    for &(file, vertices, triangles, grid) in EXPECTED {
        let path = dir.join(file);
        let (m, stats) = read_all(&path, ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.positions.len() as u64, vertices, "{file}");
        assert_eq!(stats.triangles, triangles, "{file}");
        assert_eq!(stats.short_faces, 0, "{file}");
        assert_eq!(stats.degenerate_strip_triangles, 0, "{file}");
        let r = MeshReader::open(&path, ReadOptions::default()).unwrap();
        match grid {
            Some((rows, cols)) => {
                let g = r.range_grid().unwrap_or_else(|| panic!("{file}: no range grid"));
                assert_eq!((g.rows, g.cols, g.cells.len()), (rows, cols, (rows * cols) as usize), "{file}");
                assert_eq!(g.filled() as u64, vertices, "{file}: filled cells = vertices");
                assert_eq!(r.info().face_count, None, "{file}");
            }
            None => assert!(r.range_grid().is_none(), "{file}"),
        }
    }
}

/// Counts directed edges: on a closed, consistently oriented surface every
/// directed edge occurs once and its reverse occurs too. This checks the
/// alternating winding of igea's strip, not just the triangle count.
fn assert_closed_and_oriented(path: &Path, euler: i64) {
    let mut r = MeshReader::open(path, ReadOptions { resolve_positions: false, ..ReadOptions::default() }).unwrap();
    let mut edges = HashSet::new();
    let mut chunk = TriangleChunk::new();
    let mut faces = 0i64;
    while r.next_chunk(&mut chunk).unwrap() {
        for t in &chunk.indices {
            faces += 1;
            for k in 0..3 {
                assert!(edges.insert((t[k], t[(k + 1) % 3])), "{}: directed edge {:?} twice", path.display(), (t[k], t[(k + 1) % 3]));
            }
        }
    }
    for &(a, b) in &edges {
        assert!(edges.contains(&(b, a)), "{}: boundary edge ({a}, {b})", path.display());
    }
    let v = r.vertex_count() as i64;
    assert_eq!(v - edges.len() as i64 / 2 + faces, euler, "{}: V - E + F", path.display());
}

#[test]
fn horse_and_igea_are_closed_and_consistently_oriented() {
    let Some(dir) = data_dir() else { return };
    assert_closed_and_oriented(&dir.join("cyberware_horse_mesh/horse.ply"), 2);
    assert_closed_and_oriented(&dir.join("cyberware_igea_mesh/igea.ply"), 2);
}

#[test]
fn real_headers() {
    let Some(dir) = data_dir() else { return };
    let i = read_info(&dir.join("stanford_bunny_zipper_mesh/bun_zipper.ply")).unwrap();
    assert_eq!((i.encoding.as_str(), i.vertex_count, i.face_count), ("ascii", 35947, Some(69451)));
    assert_eq!(i.comments, vec!["zipper output"]);
    assert_eq!(i.elements[0].properties, ["float x", "float y", "float z", "float confidence", "float intensity"]);
    let i = read_info(&dir.join("cyberware_igea_mesh/igea.ply")).unwrap();
    assert_eq!(i.elements[1].name, "tristrips");
    assert_eq!(i.elements[1].properties, ["list int int vertex_indices"]);
    let i = read_info(&dir.join("stanford_bunny_range_scans/bun000.ply")).unwrap();
    assert!(i.obj_info.contains(&"num_cols 512".to_string()));
}

#[test]
fn real_meshes_convert_between_formats_unchanged() {
    let Some(dir) = data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    // Ascii PLY (spilled positions) -> binary PLY (positions in place) ->
    // OBJ -> OFF -> PLY: the same float positions and faces all along
    // (exactly for PLY; OBJ and OFF hold the f32's shortest decimal).
    let src = dir.join("stanford_bunny_zipper_mesh/bun_zipper.ply");
    let want = read(&src);
    let mut prev = src;
    for name in ["b.ply", "c.obj", "d.off", "e.ply"] {
        let out = tmp.path().join(name);
        convert(&prev, &out, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap();
        let got = read(&out);
        assert_eq!(as_f32(&got), want, "{name}");
        if name.ends_with(".ply") {
            assert_eq!(got, want, "{name}");
        }
        prev = out;
    }
    // Strips come out as plain triangles.
    let igea = dir.join("cyberware_igea_mesh/igea.ply");
    let out = tmp.path().join("igea.ply");
    let s = convert(&igea, &out, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap();
    assert_eq!((s.vertices_written, s.triangles), (134345, 268686));
    assert_eq!(read(&out), read(&igea));
}
