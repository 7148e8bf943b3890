//! The real recordings, read from the shared data folder (`$MPMWATCH_DATA`, or `../shared/data`
//! next to the project). A missing file fails the test naming it: the data folder's own rule is
//! never to pass silently.

use std::path::PathBuf;

/// The shared data folder.
pub fn data_dir() -> PathBuf {
    std::env::var_os("MPMWATCH_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"))
}

/// The named columns of a headered CSV (quoted names; a blank line is skipped, a missing or
/// unparsable value in a named column fails).
pub fn read_columns(path: &PathBuf, names: &[&str]) -> Vec<Vec<f64>> {
    assert!(path.exists(), "{} not found: set MPMWATCH_DATA to the shared data folder", path.display());
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> =
        lines.next().unwrap().split(',').map(|s| s.trim().trim_matches('"').to_string()).collect();
    let idx: Vec<usize> =
        names.iter().map(|n| header.iter().position(|h| h == n).expect("column in header")).collect();
    let mut cols = vec![Vec::new(); names.len()];
    for (row, l) in lines.filter(|l| !l.trim().is_empty()).enumerate() {
        let cells: Vec<&str> = l.split(',').collect();
        for (c, &k) in idx.iter().enumerate() {
            let v = cells.get(k).and_then(|s| s.trim().parse::<f64>().ok());
            cols[c].push(v.unwrap_or_else(|| panic!("{}: row {row}, column {}", path.display(), names[c])));
        }
    }
    cols
}
