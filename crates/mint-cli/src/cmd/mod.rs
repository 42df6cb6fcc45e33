//! The `mint` subcommands (being split into one module per subcommand).

pub mod align;
pub mod check;
pub mod contours;
pub mod decimate;
pub mod gen;
pub mod render;
pub mod stage;
