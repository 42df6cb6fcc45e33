//! `mint info`: a mesh file's format, counts, elements and properties, from
//! its header alone (the body is not read). Calls `mint_io::read_info`.

use crate::jobs::{JsonArg};
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Mesh file.
    pub file: PathBuf,
    #[command(flatten)]
    pub json: JsonArg,
}

pub(crate) fn cmd_info(a: InfoArgs) -> Result<()> {
    let info = mint_io::read_info(&a.file)?;
    if a.json.json {
        let v = serde_json::json!({
            "file": a.file.display().to_string(),
            "format": format!("{:?}", info.format),
            "encoding": info.encoding,
            "vertices": info.vertex_count,
            "faces": info.face_count,
            "elements": info.elements.iter().map(|e| serde_json::json!({
                "name": e.name, "count": e.count, "properties": e.properties
            })).collect::<Vec<_>>(),
            "comments": info.comments,
            "obj_info": info.obj_info,
        });
        crate::out::json(&v)?;
    } else {
        println!("{}: {:?} ({})", a.file.display(), info.format, info.encoding);
        println!("  vertices  {}", info.vertex_count);
        match info.face_count {
            Some(n) => println!("  faces     {n}"),
            None => println!("  faces     (not stated in the header)"),
        }
        for e in &info.elements {
            println!("  element {} {}", e.name, e.count);
            for p in &e.properties {
                println!("    {p}");
            }
        }
        for c in &info.comments {
            println!("  comment {c}");
        }
        for c in &info.obj_info {
            println!("  obj_info {c}");
        }
    }
    Ok(())
}
