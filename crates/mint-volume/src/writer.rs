//! Volume writer (being written).
/// Output formats.
#[derive(Clone, Copy, Debug)]
pub enum VolumeFormat { Nrrd }
/// Writer.
pub struct VolumeWriter;
