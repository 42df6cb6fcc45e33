//! mint-store (in progress).
