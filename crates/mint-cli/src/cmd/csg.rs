//! `mint csg`: meshes a CSG scene (JSON: primitives and meshes, booleans,
//! transforms) on one grid, out of core. Calls `mint_pipeline::parse_scene`
//! and `mint_pipeline::run_scene`; the arguments (`CsgArgs`, shared with
//! `mint stage plan csg` and `mint slurm csg`) live in `jobs`.

use crate::jobs::{scene_inputs, CsgArgs};
use crate::preview::write_preview;
use crate::progress::Bars;
use crate::summary::report;
use anyhow::{Context, Result};
use mint_pipeline::Job;

pub(crate) fn cmd_csg(a: CsgArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.scene])?;
    let text = std::fs::read_to_string(&a.scene).with_context(|| format!("{}: cannot read the scene", a.scene.display()))?;
    let scene = mint_pipeline::parse_scene(&text, &a.scene)?;
    crate::paths::check_output(&a.output, &scene_inputs(&a.scene, &scene))?;
    let spec = a.run.spec(Job::Csg { scene: a.scene.clone() }, &a.output, None)?;
    let bars = Bars::new(a.run.report.silent());
    let s = mint_pipeline::run_scene(&spec, &scene, &a.run.tuning(), &bars)?;
    if a.run.preview {
        let mut meshes: Vec<Vec<std::path::PathBuf>> = scene
            .operands
            .iter()
            .filter_map(|o| match o {
                mint_pipeline::scene::Operand::Mesh { paths, .. } => Some(paths.clone()),
                _ => None,
            })
            .collect();
        meshes.push(vec![a.output.clone()]);
        write_preview(&meshes, &a.output, a.run.preview_up.up, a.run.report.silent(), &bars)?;
    }
    report(&a.run.report, &s)
}
