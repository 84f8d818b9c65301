//! Trace keys: the name a trace is recorded under in a baseline.

use std::borrow::Cow;
use std::path::{Component, Path, PathBuf};

/// The key a trace is recorded under: the path as given, without `.`
/// components or doubled separators, with `/` separators. An absolute path
/// inside the current directory is made relative to it; any other absolute
/// path is reduced to its file name, so no baseline holds a machine's
/// directory layout. `-` is `<stdin>`.
pub fn trace_key(arg: &Path, cwd: Option<&Path>) -> String {
    if arg.as_os_str() == "-" {
        return "<stdin>".to_string();
    }
    let relative: Cow<'_, Path> = if arg.is_absolute() {
        match cwd.and_then(|cwd| inside(arg, cwd)) {
            Some(rel) => Cow::Owned(rel),
            None => Cow::Borrowed(arg.file_name().map_or(arg, Path::new)),
        }
    } else {
        Cow::Borrowed(arg)
    };
    let parts: Vec<Cow<'_, str>> = relative
        .components()
        .filter_map(|c| match c {
            Component::Normal(s) => Some(s.to_string_lossy()),
            Component::ParentDir => Some(Cow::Borrowed("..")),
            Component::CurDir | Component::RootDir | Component::Prefix(_) => None,
        })
        .collect();
    if parts.is_empty() {
        return ".".to_string();
    }
    parts.join("/")
}

/// [`trace_key`] relative to `root` (`--root DIR`) instead of the current
/// directory: the same key whichever directory `check` runs in. A trace
/// outside `root` keeps its key relative to the current directory.
pub fn trace_key_under(arg: &Path, cwd: Option<&Path>, root: Option<&Path>) -> String {
    let (Some(root), Some(cwd)) = (root, cwd) else {
        return trace_key(arg, cwd);
    };
    if arg.as_os_str() == "-" {
        return trace_key(arg, Some(cwd));
    }
    let absolute = |p: &Path| match p.is_absolute() {
        true => p.to_path_buf(),
        false => cwd.join(p),
    };
    match inside(&absolute(arg), &absolute(root)) {
        Some(rel) => trace_key(&rel, None),
        None => trace_key(arg, Some(cwd)),
    }
}

/// `path` relative to `dir` when it is inside it, comparing as written and
/// then with symbolic links resolved (a shell's `$PWD` may differ from the
/// resolved current directory).
fn inside(path: &Path, dir: &Path) -> Option<PathBuf> {
    if let Ok(rel) = path.strip_prefix(dir) {
        return Some(rel.to_path_buf());
    }
    let path = path.canonicalize().ok()?;
    let dir = dir.canonicalize().ok()?;
    path.strip_prefix(&dir).ok().map(Path::to_path_buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_under_a_root_are_relative_to_it_wherever_the_cwd_is() {
        let under = |arg: &str, cwd: &str, root: &str| {
            trace_key_under(Path::new(arg), Some(Path::new(cwd)), Some(Path::new(root)))
        };
        assert_eq!(under("traces/a.log", "/p", "/p"), "traces/a.log");
        assert_eq!(under("a.log", "/p/traces", "/p"), "traces/a.log");
        assert_eq!(under("../traces/a.log", "/p/ci", ".."), "traces/a.log");
        assert_eq!(under("/p/traces/a.log", "/elsewhere", "/p"), "traces/a.log");
        // Outside the root: as without one.
        assert_eq!(under("b.log", "/q", "/p"), "b.log");
        assert_eq!(under("-", "/q", "/p"), "<stdin>");
    }

    #[test]
    fn keys_are_relative_and_normalized() {
        let cwd = Path::new("/home/ci/project");
        let key = |p: &str| trace_key(Path::new(p), Some(cwd));
        assert_eq!(key("traces/a.log"), "traces/a.log");
        assert_eq!(key("./traces//a.log"), "traces/a.log");
        assert_eq!(key("../other/a.log"), "../other/a.log");
        assert_eq!(key("/home/ci/project/traces/a.log"), "traces/a.log");
        assert_eq!(key("/tmp/x/a.log"), "a.log");
        assert_eq!(key("-"), "<stdin>");
        assert_eq!(trace_key(Path::new("/tmp/a.log"), None), "a.log");
    }
}
