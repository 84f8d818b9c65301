//! Golden files: output compared byte for byte with a file under
//! tests/golden/ (or another committed file, like the README's chart), or
//! rewritten when `UPDATE_GOLDEN` is set. Refresh after an intended change
//! with `UPDATE_GOLDEN=1 cargo test --test integration -- golden:: chart::`
//! and review the diff like code.

use std::fs;
use std::path::{Path, PathBuf};

/// The golden file of `fixture` for `suffix`: `tests/golden/NAME.SUFFIX`.
pub fn path(fixture: &Path, suffix: &str) -> PathBuf {
    let name = fixture
        .file_name()
        .and_then(|n| n.to_str())
        .expect("utf-8 name");
    Path::new("tests/golden").join(format!("{name}.{suffix}"))
}

/// The fixtures the golden files are made of: the files directly in
/// fixtures/, without the generator script, notes and profiles.
pub fn fixtures() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = fs::read_dir("fixtures")
        .expect("fixtures/ exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            !name.ends_with(".py")
                && !name.ends_with(".md")
                && !name.ends_with(".toml")
                && !name.ends_with(".dcf")
                && p.is_file()
        })
        .collect();
    files.sort();
    assert!(
        files.len() >= 15,
        "expected the fixture set, found {files:?}"
    );
    files
}

/// Compares `actual` with the file at `path`, or rewrites it under
/// `UPDATE_GOLDEN`; a difference is pushed to `failures` (so one run names
/// every stale file) with its first differing line.
pub fn check(path: &Path, actual: &str, failures: &mut Vec<String>) {
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        fs::create_dir_all(path.parent().expect("has parent")).expect("mkdir");
        fs::write(path, actual).expect("write golden");
        return;
    }
    match fs::read_to_string(path) {
        Ok(expected) if expected == actual => {}
        Ok(expected) => failures.push(format!(
            "{} differs:\n{}",
            path.display(),
            first_difference(&expected, actual)
        )),
        Err(_) => failures.push(format!(
            "{} is missing (run UPDATE_GOLDEN=1 cargo test --test integration)",
            path.display()
        )),
    }
}

/// The first differing line of two texts, for readable failures.
pub fn first_difference(expected: &str, actual: &str) -> String {
    let mut e = expected.lines();
    let mut a = actual.lines();
    let mut n = 1;
    loop {
        match (e.next(), a.next()) {
            (None, None) => return "texts differ only in line endings".to_string(),
            (x, y) if x == y => n += 1,
            (x, y) => {
                return format!(
                    "line {n}:\n  expected: {}\n  actual:   {}",
                    x.unwrap_or("<end>"),
                    y.unwrap_or("<end>")
                );
            }
        }
    }
}
