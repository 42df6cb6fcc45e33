//! TIFF stacks (being written).
use std::path::Path;
use crate::source::SliceSource;
use crate::{VolumeError, VolumeInfo};
pub(crate) fn is_stack_dir(_path: &Path) -> Result<bool, VolumeError> {
    Ok(false)
}
pub(crate) fn open(path: &Path) -> Result<(VolumeInfo, Box<dyn SliceSource>), VolumeError> {
    Err(VolumeError::unsupported(path, "TIFF stacks: not yet"))
}
