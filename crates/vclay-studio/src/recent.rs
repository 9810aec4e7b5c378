//! Recently opened files (File > Open recent): a JSON list of absolute paths, newest first, at
//! most [`MAX_RECENT`], kept in one file. A missing or unreadable list is an empty one; a list
//! that cannot be written is not an error (the studio works on).

use std::path::{Path, PathBuf};

/// Most files kept.
pub const MAX_RECENT: usize = 10;

/// The list kept in `file` (`None`, missing or unreadable: empty); entries that no longer exist
/// are left out.
pub fn load(file: Option<&Path>) -> Vec<PathBuf> {
    let Some(file) = file else { return Vec::new() };
    std::fs::read_to_string(file)
        .ok()
        .and_then(|t| serde_json::from_str::<Vec<PathBuf>>(&t).ok())
        .unwrap_or_default()
        .into_iter()
        .filter(|p| p.exists())
        .take(MAX_RECENT)
        .collect()
}

/// Puts `opened` first in the list kept in `file` (as an absolute path, once) and returns the
/// new list. Without `file` the list is just `opened`.
pub fn remember(file: Option<&Path>, opened: &Path) -> Vec<PathBuf> {
    let abs = std::fs::canonicalize(opened).unwrap_or_else(|_| opened.to_path_buf());
    let mut list = vec![abs.clone()];
    list.extend(load(file).into_iter().filter(|p| *p != abs));
    list.truncate(MAX_RECENT);
    if let Some(file) = file {
        if let Some(dir) = file.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        if let Ok(text) = serde_json::to_string_pretty(&list) {
            let tmp = file.with_extension("json.tmp");
            if std::fs::write(&tmp, text).is_ok() {
                let _ = std::fs::rename(&tmp, file);
            }
        }
    }
    list
}

/// Where the binary keeps the list: `$XDG_CONFIG_HOME/vclay/recent.json`, else
/// `$HOME/.config/vclay/recent.json` (`None` without either).
pub fn default_file() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .filter(|p| p.is_absolute())
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(base.join("vclay").join("recent.json"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_newest_comes_first_once_and_the_list_is_bounded() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("cfg/recent.json");
        let mut made = Vec::new();
        for k in 0..MAX_RECENT + 3 {
            let p = dir.path().join(format!("m{k}.toml"));
            std::fs::write(&p, "").unwrap();
            made.push(std::fs::canonicalize(&p).unwrap());
            remember(Some(&file), &p);
        }
        remember(Some(&file), &made[5]);
        let list = load(Some(&file));
        assert_eq!(list.len(), MAX_RECENT);
        assert_eq!(list[0], made[5]);
        assert_eq!(list[1], made[MAX_RECENT + 2]);
        assert_eq!(list.iter().filter(|p| **p == made[5]).count(), 1);
        // Gone files drop out; a broken list is an empty one.
        std::fs::remove_file(&made[5]).unwrap();
        assert!(!load(Some(&file)).contains(&made[5]));
        std::fs::write(&file, "not json").unwrap();
        assert!(load(Some(&file)).is_empty());
        assert!(load(None).is_empty());
    }
}
