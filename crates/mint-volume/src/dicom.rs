//! DICOM series (being written).
use std::path::Path;
use crate::source::SliceSource;
use crate::{VolumeError, VolumeInfo};
pub(crate) fn open(path: &Path) -> Result<(VolumeInfo, Box<dyn SliceSource>), VolumeError> {
    Err(VolumeError::unsupported(path, "DICOM series: not yet"))
}
