//! Reading and writing recordings: the time-aligned data table and its CSV form (DESIGN.md §4.1).

mod table;

pub use table::{Table, TableError};
