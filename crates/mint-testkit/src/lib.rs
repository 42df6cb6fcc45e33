//! mint-testkit (in progress).
