//! Shared test helpers.

/// The first place where two JSON values differ (`None` if equal), with both values
/// shortened: keeps failure messages readable when saved models are large.
pub fn first_difference(a: &serde_json::Value, b: &serde_json::Value) -> Option<String> {
    use serde_json::Value;
    fn go(a: &Value, b: &Value, path: &str) -> Option<String> {
        match (a, b) {
            (Value::Object(x), Value::Object(y)) => {
                for (k, v) in x {
                    match y.get(k) {
                        Some(w) => {
                            if let Some(d) = go(v, w, &format!("{path}.{k}")) {
                                return Some(d);
                            }
                        }
                        None => return Some(format!("{path}.{k}: missing on the right")),
                    }
                }
                y.keys()
                    .find(|k| !x.contains_key(*k))
                    .map(|k| format!("{path}.{k}: missing on the left"))
            }
            (Value::Array(x), Value::Array(y)) => {
                if x.len() != y.len() {
                    return Some(format!("{path}: lengths {} and {}", x.len(), y.len()));
                }
                x.iter()
                    .zip(y)
                    .enumerate()
                    .find_map(|(i, (v, w))| go(v, w, &format!("{path}[{i}]")))
            }
            _ if a == b => None,
            _ => {
                let s = |v: &Value| v.to_string().chars().take(80).collect::<String>();
                Some(format!("{path}: {} != {}", s(a), s(b)))
            }
        }
    }
    go(a, b, "")
}

/// Asserts equality of two JSON values, naming the first difference.
#[track_caller]
pub fn assert_same(a: &serde_json::Value, b: &serde_json::Value, what: &str) {
    if let Some(d) = first_difference(a, b) {
        panic!("{what}: {d}");
    }
}
