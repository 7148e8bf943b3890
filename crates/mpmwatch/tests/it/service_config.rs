//! `mpmwatch serve` refuses a bad configuration with a non-zero exit and one line per problem,
//! each naming its key; the shipped configs pass `--check`.

use std::process::Command;

fn serve(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_mpmwatch")).arg("serve").args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn bad_config_exits_non_zero_with_one_line_per_problem() {
    let dir = std::env::temp_dir().join(format!("mpmwatch-config-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.toml");
    std::fs::write(
        &path,
        r#"
prefix = "a/b"
[zenoh]
mode = "satellite"
[http]
bind = "everywhere"
[[controller]]
id = "c1"
period = -1
mv = ["u1", "u2"]
dither = ["ud1"]
cv = ["y1"]
pred = ["p1"]
surrogates = 1
"#,
    )
    .unwrap();
    let (code, err) = serve(&["--config", path.to_str().unwrap()]);
    assert_ne!(code, 0);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(lines.len(), 6, "{err}");
    for key in [
        "prefix:",
        "zenoh.mode:",
        "http.bind:",
        "(\"c1\").period:",
        "(\"c1\").dither:",
        "(\"c1\").surrogates:",
    ] {
        assert!(lines.iter().any(|l| l.contains(key)), "{key} not named in\n{err}");
    }
    std::fs::write(&path, "[[controller]]\nid = \"c1\"\nwindw = 3\n").unwrap();
    let (code, err) = serve(&["--config", path.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(err.contains("windw"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn shipped_configs_pass_the_check() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    for f in [
        "config/default.toml",
        "config/examples/continuous2x3.toml",
        "config/examples/model-residual.toml",
        "config/examples/split-a.toml",
        "config/examples/split-b.toml",
    ] {
        let (code, err) = serve(&["--config", &format!("{root}/{f}"), "--check"]);
        assert_eq!(code, 0, "{f}: {err}");
    }
}
