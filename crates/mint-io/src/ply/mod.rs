//! Stanford PLY: the header parser ([`header`]), the streaming reader
//! ([`read`]) and the writer ([`write`]). The reader handles ascii and
//! binary little/big-endian bodies, elements in any order, `face`,
//! `tristrips` and `range_grid` elements; the writer emits binary
//! little-endian or ascii with a fixed-size header patched at the end.

pub(crate) mod header;
pub(crate) mod read;
pub(crate) mod write;
