//! The CSV reader on arbitrary bytes: an error or a table, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(t) = mpmwatch_core::io::Table::from_reader(data, std::path::Path::new("fuzz.csv")) {
        for name in t.names() {
            assert_eq!(t.column(name).map(|c| c.len()).ok(), Some(t.len()));
        }
    }
});
