//! One hook for progress and cancellation, polled between stages, per chunk
//! of faces, per slab and per scan. The default methods do nothing, so
//! [`NoProgress`] is the null hook. (A trait and an enum only: mint-core
//! still does no I/O; the CLI draws the bars.)

/// The long phases of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Reading vertex positions to find the bounding box (units: vertices).
    Bounds,
    /// Streaming faces and discretizing them (units: faces).
    Discretize,
    /// Reconstructing slabs (units: layers).
    Reconstruct,
    /// Copying the faces into the output after its vertices (units: faces).
    Write,
    /// Reading range scans (units: scans).
    LoadScans,
    /// Registering scans by ICP (units: scans).
    Register,
    /// Zippering scans into the model (units: scans).
    Zipper,
    /// Consensus geometry, two passes over the scans (units: scan passes).
    Consensus,
    /// Discretizing scans on the grid merge's grid (units: scans).
    GridMerge,
    /// Reading the sections of a contour stack (units: sections).
    Sections,
    /// Reconstructing a surface from contour sections (units: sections).
    Contours,
    /// Cutting a mesh into sections (units: bytes of the input).
    Slice,
    /// Drawing a mesh's triangles (units: faces).
    Render,
}

impl Phase {
    pub fn name(self) -> &'static str {
        match self {
            Phase::Bounds => "bounds",
            Phase::Discretize => "discretize",
            Phase::Reconstruct => "reconstruct",
            Phase::Write => "write",
            Phase::LoadScans => "load scans",
            Phase::Register => "register",
            Phase::Zipper => "zipper",
            Phase::Consensus => "consensus",
            Phase::GridMerge => "grid merge",
            Phase::Sections => "sections",
            Phase::Contours => "contours",
            Phase::Slice => "slice",
            Phase::Render => "render",
        }
    }
}

/// Receives progress and may ask the pipeline to stop.
pub trait Progress: Sync {
    /// A phase starts with `total` units of work (0 when unknown).
    fn start(&self, _phase: Phase, _total: u64) {}
    /// `n` more units of the current phase are done.
    fn advance(&self, _n: u64) {}
    /// The current phase is over.
    fn finish(&self) {}
    /// True when the user asked to stop (Ctrl-C); the pipeline then cleans
    /// up and returns its `Cancelled` error (mint-pipeline's `PipelineError`,
    /// mint-range's `RangeError`).
    fn cancelled(&self) -> bool {
        false
    }
}

/// The null hook.
pub struct NoProgress;
impl Progress for NoProgress {}
