//! mint-pipeline (in progress).
