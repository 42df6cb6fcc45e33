//! Voxel volumes read slice by slice (placeholder: being written).
