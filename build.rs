//! Records the git commit the binary was built from, for `summary.json`.
//! A build outside a git checkout records "unknown".

fn git(args: &[&str]) -> Option<String> {
    std::process::Command::new("git")
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
}

fn main() {
    let commit = git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".to_string());
    println!("cargo:rustc-env=QUADSIM_GIT_COMMIT={commit}");
    // HEAD lives in the checkout's git directory (a linked worktree has its
    // own, `.git` being a file there), the branches in the common one; a
    // path that does not exist would make cargo rebuild on every build.
    match (
        git(&["rev-parse", "--git-dir"]),
        git(&["rev-parse", "--git-common-dir"]),
    ) {
        (Some(dir), Some(common)) => {
            println!("cargo:rerun-if-changed={dir}/HEAD");
            println!("cargo:rerun-if-changed={common}/refs/heads");
        }
        _ => println!("cargo:rerun-if-changed=build.rs"),
    }
}
