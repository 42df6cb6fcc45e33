//! The integration suite: round trips between every format and option
//! (`roundtrip`), hand-made files exercising format features (`features`),
//! the real scans in shared/data (`real_data`), one test per kind of bad
//! input or failing output (`bad_input`), and a multi-million-triangle
//! streaming test under a heap limit (`streaming`), and the direct record
//! path against the streaming reader (`visit`). Shared helpers live in
//! `util`.
mod bad_input;
mod colour;
mod features;
mod gltf;
mod tiles;
mod real_data;
mod roundtrip;
mod streaming;
mod visit;
pub mod util;
