//! The plan of a staged run (`DIR/plan.json`): the run's [`RunSpec`] as
//! it is (what decides the output), its [`Tuning`] (the defaults of its
//! tasks), its split into parts and slabs, the fingerprints of every input
//! file, and the stages in order with their task counts. Every task count
//! is known here, before any work, so that a whole run can be submitted to
//! a scheduler at once.
//!
//! The grid itself is not in the plan: it follows from the input's bounds,
//! which the first stage computes in parallel; every later task reduces the
//! bounds stage's small per-task files to the same grid. Likewise the slabs
//! are a fixed number of layer ranges, drawn from the discretize stage's
//! per-plane counts by one deterministic rule (equal shares of records).
//!
//! `plan.json` is plain JSON (`jq` and Python's `json.load` read it) with
//! its checksum inside: `crc32` is the CRC-32 of the compact JSON of every
//! other field, keys sorted. A plan of another format version or mint
//! version, a damaged or edited one, a missing field or an unknown value
//! anywhere is refused with one line naming the file and the field; a
//! plan's claims (stages, task counts) are checked against what its spec,
//! parts and slabs imply before any task trusts them.

use crate::error::PipelineError;
use crate::scene::{Operand, Scene};
use crate::spec::{Job, RunSpec, Tuning};
pub use crate::workdir::Stage;
use crate::workdir::{write_atomic, PLAN_FILE};
use mint_io::{MeshReader, MeshWriter, ReadOptions};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

pub use crate::spec::absolute;

/// The plan format's version; a plan of another version is refused.
/// 2: plain JSON with the checksum inside, the run spec embedded as it is.
/// 3: a surface may be several files (`inputs`, `files`).
pub const PLAN_VERSION: u32 = 5;
const PLAN_FORMAT: &str = "mint stage plan";
/// The most parts or slabs a run may be split into.
pub const MAX_TASKS: u32 = 1 << 16;

/// What identifies an input file: path, size, modification time, and a
/// CRC-32 of its first 64 KiB, its last 4 KiB and eight 4 KiB blocks spread
/// over the rest.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fingerprint {
    pub path: PathBuf,
    pub size: u64,
    pub mtime_ns: u128,
    pub sample_crc32: u32,
}

impl Fingerprint {
    pub fn of(path: &Path) -> Result<Fingerprint, PipelineError> {
        let err = |op| move |source| PipelineError::Temp { path: path.to_path_buf(), op, source };
        let mut f = std::fs::File::open(path).map_err(err("opening an input"))?;
        let meta = f.metadata().map_err(err("reading an input's metadata"))?;
        let size = meta.len();
        let mtime_ns = meta.modified().ok().and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok()).map_or(0, |d| d.as_nanos());
        let mut crc = crc32fast::Hasher::new();
        let mut blocks: Vec<(u64, u64)> = vec![(0, 64 << 10)];
        for i in 1..=8u64 {
            blocks.push((size / 9 * i, 4 << 10));
        }
        blocks.push((size.saturating_sub(4 << 10), 4 << 10));
        let mut buf = vec![0u8; 64 << 10];
        for (at, len) in blocks {
            let len = len.min(size.saturating_sub(at)) as usize;
            f.seek(SeekFrom::Start(at)).map_err(err("reading an input"))?;
            f.read_exact(&mut buf[..len]).map_err(err("reading an input"))?;
            crc.update(&buf[..len]);
        }
        Ok(Fingerprint { path: path.to_path_buf(), size, mtime_ns, sample_crc32: crc.finalize() })
    }
}

/// One file of a mesh operand: its vertex count, its size, and its
/// face-record count when its faces can be read in ranges (binary PLY,
/// binary STL). Other files are read whole by one part.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshFile {
    pub path: PathBuf,
    pub bytes: u64,
    /// The vertex count when planning knows it; `None` for text formats,
    /// whose vertices are counted as the bounds stage reads them (planning
    /// does not read a text file twice).
    pub vertices: Option<u64>,
    pub split_faces: Option<u64>,
    /// Tiles read from a 3D Tiles tileset (0 for other files).
    #[serde(default)]
    pub tiles: u64,
    /// The file has per-vertex colour (an OBJ's first `v` line decides).
    #[serde(default)]
    pub colour: bool,
}

/// What the plan knows of one operand of the scene.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OperandPlan {
    /// A surface of one or more mesh files, in the engine's order.
    Mesh { files: Vec<MeshFile> },
    /// An analytic primitive (computed on demand; nothing to read).
    Primitive,
    /// A voxel volume (its files are among the plan's inputs).
    Volume,
}

/// One stage and its task count.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StagePlan {
    pub name: Stage,
    pub tasks: u32,
}

/// A staged run's plan; see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    pub format: String,
    pub version: u32,
    pub mint_version: String,
    pub spec: RunSpec,
    pub parts: u32,
    pub slabs: u32,
    pub inputs: Vec<Fingerprint>,
    pub operands: Vec<OperandPlan>,
    pub stages: Vec<StagePlan>,
    pub tuning: Tuning,
}

/// The stages of a run of `spec` in `parts` and `slabs`, with their tasks.
fn stages_of(spec: &RunSpec, has_mesh: bool, parts: u32, slabs: u32) -> Vec<StagePlan> {
    let strict = spec.strict();
    let mut stages = vec![StagePlan { name: Stage::Bounds, tasks: parts }, StagePlan { name: Stage::Discretize, tasks: parts }];
    if has_mesh && !strict {
        stages.push(StagePlan { name: Stage::Census, tasks: slabs });
    }
    stages.push(StagePlan { name: Stage::Reconstruct, tasks: slabs });
    if !strict && spec.max_hole.is_some() {
        stages.push(StagePlan { name: Stage::Reopen, tasks: slabs });
    }
    stages.push(StagePlan { name: Stage::Write, tasks: 1 });
    stages
}

/// The checksum of a plan's JSON value (every field but `crc32`).
fn crc_of(v: &Value) -> String {
    let mut v = v.clone();
    if let Some(o) = v.as_object_mut() {
        o.remove("crc32");
    }
    format!("{:08x}", crc32fast::hash(serde_json::to_string(&v).expect("JSON values serialize").as_bytes()))
}

/// Sets `v`'s `crc32` to the checksum of its other fields (also for
/// tests that edit a plan on purpose).
pub fn seal(v: &mut Value) {
    let crc = crc_of(v);
    if let Some(o) = v.as_object_mut() {
        o.insert("crc32".into(), Value::String(crc));
    }
}

/// The first place where `a` and `b` differ, as a dotted path, with both values.
fn first_difference(a: &Value, b: &Value, path: &str) -> Option<(String, Value, Value)> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            for (k, va) in x {
                let p = if path.is_empty() { k.clone() } else { format!("{path}.{k}") };
                match y.get(k) {
                    Some(vb) => {
                        if let Some(d) = first_difference(va, vb, &p) {
                            return Some(d);
                        }
                    }
                    None => return Some((p, va.clone(), Value::Null)),
                }
            }
            None
        }
        _ if a == b => None,
        _ => Some((path.to_string(), a.clone(), b.clone())),
    }
}

/// Opens every file of a surface (headers; a text file only for its format)
/// on up to `threads` threads: many tiles are many files. The results come
/// back in the files' order.
fn open_all(paths: &[PathBuf], threads: usize) -> Vec<Result<MeshFile, mint_io::Error>> {
    let open = |path: &PathBuf| -> Result<MeshFile, mint_io::Error> {
        let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
        // Text formats cannot be split, and opening one parses (and
        // spills) every vertex, counting them a full scan: the bounds stage
        // reads and counts them, in parallel parts.
        use mint_io::Format::*;
        if matches!(mint_io::Format::from_path(path)?, Obj | Off | Mesh | Raw) {
            let colour = mint_io::has_vertex_colour(path)?;
            return Ok(MeshFile { path: path.clone(), bytes, vertices: None, split_faces: None, tiles: 0, colour });
        }
        let r = MeshReader::open(path, ReadOptions { chunk_triangles: 1, spill_dir: Some(std::env::temp_dir()), resolve_positions: false })?;
        let tiles = r.info().elements.iter().find(|e| r.info().format == mint_io::Format::Tiles && e.name == "tiles").map_or(0, |e| e.count);
        Ok(MeshFile { path: path.clone(), bytes, vertices: Some(r.vertex_count() as u64), split_faces: r.splittable_records(), tiles, colour: r.colours().is_some() || r.face_colours().is_some() || r.texturing().is_some() })
    };
    // Every file is opened (the first error in file order is reported);
    // each worker keeps what it opened, by index.
    let (_, opened, ()) = mint_core::pool::run(
        threads.clamp(1, paths.len().max(1)),
        paths.len() as u64,
        |_| Vec::new(),
        |got: &mut Vec<(usize, Result<MeshFile, mint_io::Error>)>, k| -> Result<(), ()> {
            got.push((k as usize, open(&paths[k as usize])));
            Ok(())
        },
        |got| got,
        |_| (),
    );
    let mut opened: Vec<(usize, Result<MeshFile, mint_io::Error>)> = opened.into_iter().flatten().collect();
    opened.sort_by_key(|o| o.0);
    opened.into_iter().map(|o| o.1).collect()
}

impl Plan {
    /// Plans `spec` (whose scene is `scene`) with `tuning`'s parts and slabs.
    pub fn new(spec: &RunSpec, scene: &Scene, tuning: &Tuning) -> Result<Plan, PipelineError> {
        let spec = RunSpec { job: spec.job.absolute(), output: absolute(&spec.output), ..spec.normalized() };
        let (parts, slabs) = (tuning.parts.max(1), tuning.slabs.max(1));
        for (what, n) in [("--parts", parts), ("--slabs", slabs)] {
            if n > MAX_TASKS {
                return Err(PipelineError::stage(&spec.output, format!("{what} {n}: at most {MAX_TASKS}")));
            }
        }
        let mut operands = Vec::new();
        let mut files: Vec<PathBuf> = Vec::new();
        if let Job::Csg { scene } = &spec.job {
            if scene.is_file() {
                files.push(scene.clone());
            }
        }
        for op in &scene.operands {
            operands.push(match op {
                Operand::Primitive(_) => OperandPlan::Primitive,
                Operand::Volume(v) => {
                    // The header is checked now, before any work.
                    for f in v.open()?.info().files.iter() {
                        let f = absolute(f);
                        if !files.contains(&f) {
                            files.push(f);
                        }
                    }
                    OperandPlan::Volume
                }
                Operand::Mesh { paths, .. } => {
                    let mut mesh_files = Vec::with_capacity(paths.len());
                    for (k, opened) in open_all(paths, tuning.thread_count()).into_iter().enumerate() {
                        let mut f = opened.map_err(|e| crate::error::in_file_list(e.into(), k, paths.len()))?;
                        f.path = absolute(&f.path);
                        if !files.contains(&f.path) {
                            files.push(f.path.clone());
                        }
                        mesh_files.push(f);
                    }
                    OperandPlan::Mesh { files: mesh_files }
                }
            });
        }
        let inputs = files.iter().map(|f| Fingerprint::of(f)).collect::<Result<Vec<_>, _>>()?;
        let has_mesh = operands.iter().any(|o| matches!(o, OperandPlan::Mesh { .. }));
        let stages = stages_of(&spec, has_mesh, parts, slabs);
        let work_dir = tuning.work_dir.as_deref().map(absolute);
        Ok(Plan {
            format: PLAN_FORMAT.into(),
            version: PLAN_VERSION,
            mint_version: env!("CARGO_PKG_VERSION").into(),
            spec,
            parts,
            slabs,
            inputs,
            operands,
            stages,
            tuning: Tuning { work_dir, parts, slabs, ..tuning.clone() },
        })
    }

    /// Tasks of `stage` (0 when the plan has no such stage).
    pub fn tasks(&self, stage: Stage) -> u32 {
        self.stages.iter().find(|s| s.name == stage).map_or(0, |s| s.tasks)
    }

    pub fn has_stage(&self, stage: Stage) -> bool {
        self.stages.iter().any(|s| s.name == stage)
    }

    /// True when the run carries colour: some input file has it, the
    /// output's format holds it, and `--no-color` was not given. Every
    /// shard store of a coloured run holds coloured records (files without
    /// colour count as white).
    pub fn coloured(&self) -> bool {
        // A volume operand has no colour to carry: its scene's output is white.
        !self.spec.write.no_colour
            && self.input_coloured()
            && !self.operands.iter().any(|o| matches!(o, OperandPlan::Volume))
            && mint_io::Format::from_path(&self.spec.output).is_ok_and(MeshWriter::holds_colour)
    }

    /// True when some input mesh file has per-vertex colour.
    pub fn input_coloured(&self) -> bool {
        self.operands.iter().any(|o| matches!(o, OperandPlan::Mesh { files } if files.iter().any(|f| f.colour)))
    }

    /// True for a strict `--signs orient` resampling (the paper's rule).
    pub fn strict(&self) -> bool {
        self.spec.strict()
    }

    /// The plan's text: pretty JSON with its checksum.
    pub fn to_json(&self) -> String {
        let mut v = serde_json::to_value(self).expect("plans serialize");
        seal(&mut v);
        serde_json::to_string_pretty(&v).expect("JSON values serialize") + "\n"
    }

    /// Writes the plan to `DIR/plan.json`, atomically.
    pub fn save(&self, dir: &Path) -> Result<(), PipelineError> {
        write_atomic(&dir.join(PLAN_FILE), self.to_json().as_bytes())
    }

    /// Reads `DIR/plan.json`; see the module docs for what is refused.
    pub fn load(dir: &Path) -> Result<Plan, PipelineError> {
        let path = dir.join(PLAN_FILE);
        if !path.is_file() {
            return Err(PipelineError::stage(dir, "no plan.json: not a work directory (make one with `mint stage plan`)"));
        }
        let bytes = std::fs::read(&path).map_err(|source| PipelineError::Temp { path: path.clone(), op: "reading", source })?;
        Plan::parse(&bytes, &path)
    }

    /// Reads a plan from `bytes` (the file `path`).
    pub fn parse(bytes: &[u8], path: &Path) -> Result<Plan, PipelineError> {
        let refuse = |what: String| PipelineError::stage(path, what);
        let other_version = |version: &str, by: &str| {
            refuse(format!(
                "a plan of format {version} written by mint {by}; this is mint {} (plan format {PLAN_VERSION}): finish the run with that version, or plan it again in a new directory",
                env!("CARGO_PKG_VERSION")
            ))
        };
        if bytes.starts_with(b"crc32 ") {
            return Err(other_version("1", "0.1.0 or older"));
        }
        let v: Value = serde_json::from_slice(bytes).map_err(|e| refuse(format!("not a plan: unreadable JSON ({e})")))?;
        if !v.is_object() {
            return Err(refuse("not a plan: not a JSON object".into()));
        }
        let (format, version, by) = (v["format"].as_str(), v["version"].as_u64(), v["mint_version"].as_str().unwrap_or("?"));
        if format != Some(PLAN_FORMAT) {
            return Err(refuse(format!("not a plan: field 'format' is {}, not \"{PLAN_FORMAT}\"", v["format"])));
        }
        if version != Some(PLAN_VERSION as u64) || by != env!("CARGO_PKG_VERSION") {
            return Err(other_version(&version.map_or("?".to_string(), |v| v.to_string()), by));
        }
        match v["crc32"].as_str() {
            None => return Err(refuse("damaged plan: field 'crc32' is missing; plan the run again in a new directory".into())),
            Some(c) if c != crc_of(&v) => {
                return Err(refuse("damaged or edited plan (checksum mismatch); plan the run again in a new directory".into()))
            }
            _ => {}
        }
        let mut body = v;
        body.as_object_mut().expect("an object").remove("crc32");
        let plan: Plan = serde_path_to_error::deserialize(body).map_err(|e| {
            let field = e.path().to_string();
            refuse(format!("field '{field}': {}", e.into_inner()))
        })?;
        plan.check_claims(path)?;
        Ok(plan)
    }

    /// Checks what the plan claims against what its own spec implies.
    fn check_claims(&self, path: &Path) -> Result<(), PipelineError> {
        let refuse = |what: String| Err(PipelineError::stage(path, format!("{what}; plan the run again in a new directory")));
        for (what, n) in [("parts", self.parts), ("slabs", self.slabs)] {
            if n == 0 || n > MAX_TASKS {
                return refuse(format!("field '{what}': {n} is not in 1..={MAX_TASKS}"));
            }
        }
        let scene_operands = match &self.spec.job {
            Job::Resample { .. } => Some((1, "resample")),
            Job::Bool { .. } => Some((2, "bool")),
            Job::Csg { .. } => None,
            Job::Volume(_) => Some((1, "volume")),
        };
        if let Some((n, kind)) = scene_operands.filter(|(n, _)| *n != self.operands.len()) {
            return refuse(format!("field 'operands': {} operands for a {kind} job (it has {n})", self.operands.len()));
        }
        let has_mesh = self.operands.iter().any(|o| matches!(o, OperandPlan::Mesh { .. }));
        if self.stages != stages_of(&self.spec, has_mesh, self.parts, self.slabs) {
            return refuse("field 'stages': not the stages its spec, parts and slabs imply".into());
        }
        if let Err(e) = self.spec.validate() {
            return refuse(format!("field 'spec': {e}"));
        }
        Ok(())
    }

    /// Checks the plan's operands against the scene its spec describes
    /// (kinds, files), before any task indexes one by the other.
    pub fn check_scene(&self, scene: &Scene, path: &Path) -> Result<(), PipelineError> {
        let refuse = |what: String| Err(PipelineError::stage(path, format!("field 'operands': {what}; plan the run again in a new directory")));
        if self.operands.len() != scene.operands.len() {
            return refuse(format!("{} operands, the scene has {}", self.operands.len(), scene.operands.len()));
        }
        for (j, (p, o)) in self.operands.iter().zip(&scene.operands).enumerate() {
            match (p, o) {
                (OperandPlan::Primitive, Operand::Primitive(_)) | (OperandPlan::Volume, Operand::Volume(_)) => {}
                (OperandPlan::Mesh { files }, Operand::Mesh { paths, .. }) => {
                    if files.len() != paths.len() || files.iter().zip(paths).any(|(f, p)| f.path != absolute(p)) {
                        return refuse(format!("operand {j}: not the files of the scene's surface"));
                    }
                }
                _ => return refuse(format!("operand {j}: not the kind of the scene's operand")),
            }
        }
        Ok(())
    }

    /// Checks that this (freshly made) plan describes the same run as the
    /// stored `other`: same spec, split and input files.
    pub fn check_same_run(&self, other: &Plan, dir: &Path) -> Result<(), PipelineError> {
        let what = if self.inputs != other.inputs {
            let changed = self.inputs.iter().zip(&other.inputs).find(|(a, b)| a != b).map(|(a, _)| a.path.display().to_string());
            match changed {
                Some(p) => format!("the input {p} is not the file this run was planned for (size, time or content changed)"),
                None => "the run was planned for other input files".to_string(),
            }
        } else if self.spec.job != other.spec.job || self.operands != other.operands {
            "the run was planned for another job (inputs or scene)".to_string()
        } else if self.spec.output != other.spec.output {
            format!("the run was planned to write {}", other.spec.output.display())
        } else if self.spec != other.spec {
            let a = serde_json::to_value(&self.spec).expect("specs serialize");
            let b = serde_json::to_value(&other.spec).expect("specs serialize");
            let (key, here, there) = first_difference(&a, &b, "spec").unwrap_or_default();
            format!("the run was planned with other options ({key}: {there} there, {here} here)")
        } else if (self.parts, self.slabs) != (other.parts, other.slabs) {
            format!("the run was planned with {} parts and {} slabs", other.parts, other.slabs)
        } else {
            return Ok(());
        };
        Err(PipelineError::stage(dir.join(PLAN_FILE), format!("{what}; use another work directory, or remove this one to start over")))
    }
}

/// The part of `n` items that part `i` of `parts` takes, in whole chunks.
pub fn part_range(n: u64, parts: u32, i: u32, chunk: u64) -> (u64, u64) {
    let chunks = n.div_ceil(chunk);
    let at = |j: u32| (chunks * j as u64 / parts as u64 * chunk).min(n);
    (at(i), at(i + 1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use mint_core::grid::GridSize;

    fn plan() -> Plan {
        let spec = RunSpec::resample("/data/in.ply", "/data/out.ply", GridSize::Cells(1000));
        let (parts, slabs) = (3, 2);
        let operands = vec![OperandPlan::Mesh { files: vec![MeshFile { path: "/data/in.ply".into(), bytes: 100, vertices: Some(4), split_faces: Some(4), tiles: 0, colour: false }] }];
        Plan {
            format: PLAN_FORMAT.into(),
            version: PLAN_VERSION,
            mint_version: env!("CARGO_PKG_VERSION").into(),
            stages: stages_of(&spec, true, parts, slabs),
            spec,
            parts,
            slabs,
            inputs: vec![Fingerprint { path: "/data/in.ply".into(), size: 100, mtime_ns: 1, sample_crc32: 2 }],
            operands,
            tuning: Tuning { parts, slabs, ..Default::default() },
        }
    }

    /// `plan.json` edited by `f`, resealed unless `reseal` is false, then read.
    fn edited(f: impl FnOnce(&mut Value), reseal: bool) -> Result<Plan, String> {
        let mut v: Value = serde_json::from_str(&plan().to_json()).unwrap();
        f(&mut v);
        if reseal {
            seal(&mut v);
        }
        Plan::parse(serde_json::to_string_pretty(&v).unwrap().as_bytes(), Path::new("w/plan.json")).map_err(|e| e.to_string())
    }

    fn refused(f: impl FnOnce(&mut Value), needles: &[&str]) {
        let e = edited(f, true).unwrap_err();
        assert!(!e.contains('\n') && e.starts_with("w/plan.json: "), "not one line naming the file: {e}");
        for n in needles {
            assert!(e.contains(n), "'{n}' not in: {e}");
        }
    }

    #[test]
    fn a_plan_is_plain_json_and_reads_back_as_it_was() {
        let p = plan();
        let text = p.to_json();
        let v: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["spec"]["signs"], "auto");
        assert_eq!(v["stages"][2]["name"], "census");
        assert_eq!(v["crc32"].as_str().unwrap().len(), 8);
        assert_eq!(Plan::parse(text.as_bytes(), Path::new("plan.json")).unwrap(), p);
    }

    #[test]
    fn unknown_values_and_missing_fields_are_refused_by_name() {
        refused(|v| v["spec"]["signs"] = "sideways".into(), &["field 'spec.signs'", "unknown value 'sideways'", "auto, orient, union, parity"]);
        refused(|v| v["stages"][1]["name"] = "polish".into(), &["field 'stages[1].name'", "unknown value 'polish'"]);
        refused(|v| v["spec"]["job"]["kind"] = "melt".into(), &["field 'spec.job.kind'", "melt"]);
        refused(|v| v["spec"]["grid"]["axis"] = "w".into(), &["field 'spec.grid.axis'", "unknown value 'w'"]);
        refused(|v| v["tuning"]["deref"] = "guess".into(), &["field 'tuning.deref'", "unknown value 'guess'"]);
        refused(|v| drop(v["spec"]["grid"].as_object_mut().unwrap().remove("size")), &["field 'spec.grid'", "missing field `size`"]);
        refused(|v| drop(v.as_object_mut().unwrap().remove("tuning")), &["missing field `tuning`"]);
        refused(|v| v["spec"]["colour"] = true.into(), &["field 'spec.colour'", "unknown field `colour`"]);
        refused(|v| v["spec"]["grid"]["size"] = serde_json::json!({"cells": 0}), &["field 'spec'", "--cells must be at least 1"]);
    }

    #[test]
    fn claims_a_spec_does_not_imply_are_refused() {
        // The stall of a crafted plan: four billion tasks in one stage.
        refused(|v| v["stages"][5]["tasks"] = u32::MAX.into(), &["field 'stages'", "not the stages its spec, parts and slabs imply"]);
        refused(|v| v["stages"].as_array_mut().unwrap().truncate(2), &["field 'stages'"]);
        refused(|v| v["parts"] = 0.into(), &["field 'parts'", "not in 1..="]);
        refused(|v| v["slabs"] = (MAX_TASKS + 1).into(), &["field 'slabs'"]);
        refused(|v| v["operands"].as_array_mut().unwrap().clear(), &["field 'operands'", "0 operands for a resample job"]);
    }

    #[test]
    fn damaged_edited_and_old_plans_are_refused() {
        let e = edited(|v| v["spec"]["max_hole"] = 3.into(), false).unwrap_err();
        assert!(e.contains("damaged or edited plan (checksum mismatch)"), "{e}");
        let e = edited(|v| drop(v.as_object_mut().unwrap().remove("crc32")), false).unwrap_err();
        assert!(e.contains("field 'crc32' is missing"), "{e}");
        refused(|v| v["version"] = 1.into(), &["a plan of format 1"]);
        refused(|v| v["format"] = "something else".into(), &["not a plan: field 'format'"]);
        let old = b"crc32 0badf00d\n{\"format\": \"mint stage plan\"}\n";
        let e = Plan::parse(old, Path::new("w/plan.json")).unwrap_err().to_string();
        assert!(e.contains("a plan of format 1") && !e.contains('\n'), "{e}");
        let e = Plan::parse(b"{\"format\": ", Path::new("w/plan.json")).unwrap_err().to_string();
        assert!(e.contains("not a plan: unreadable JSON"), "{e}");
    }
}
