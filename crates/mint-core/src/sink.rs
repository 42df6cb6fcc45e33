//! Where meshes go. Algorithms and generators never write files; they push
//! vertices and faces into a [`MeshSink`], and the caller picks the sink: an
//! in-core mesh, a streaming file writer, a counter.
//!
//! Contract: every vertex is pushed before the first face, and faces refer to
//! vertices by their 0-based push order. Orientation is counter-clockwise seen
//! from outside (the right-hand normal points out of the solid).

/// Any error a sink may raise (I/O, a full disk, a cancelled run).
pub type SinkError = Box<dyn std::error::Error + Send + Sync + 'static>;

/// A consumer of a streamed indexed triangle mesh.
pub trait MeshSink {
    /// Appends one vertex; its index is the number of vertices pushed before it.
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), SinkError>;
    /// Appends one vertex with its colour (RGBA bytes); sinks that keep no
    /// colour drop it.
    fn vertex_rgba(&mut self, p: [f64; 3], _rgba: [u8; 4]) -> Result<(), SinkError> {
        self.vertex(p)
    }
    /// Appends one triangle by vertex indices.
    fn face(&mut self, f: [u32; 3]) -> Result<(), SinkError>;
}

/// A sink that only counts; handy for dry runs and tests.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct CountingSink {
    pub vertices: u64,
    pub faces: u64,
}

impl MeshSink for CountingSink {
    fn vertex(&mut self, _p: [f64; 3]) -> Result<(), SinkError> {
        self.vertices += 1;
        Ok(())
    }
    fn face(&mut self, _f: [u32; 3]) -> Result<(), SinkError> {
        self.faces += 1;
        Ok(())
    }
}

/// An in-memory triangle mesh, the simplest sink. Large meshes should go
/// through a streaming writer instead.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
}

impl MeshSink for TriMesh {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), SinkError> {
        self.positions.push(p);
        Ok(())
    }
    fn face(&mut self, f: [u32; 3]) -> Result<(), SinkError> {
        self.faces.push(f);
        Ok(())
    }
}
