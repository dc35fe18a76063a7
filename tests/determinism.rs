//! The conformal core gives the same bits natively as in the browser: the digests of
//! `tests/digest/expected.txt` are checked here and, in headless Chromium, by `tests/wasm.rs`
//! (`wasm-pack test --headless --chrome --release -- --test wasm`).
//!
//! When a deliberate change alters the numbers, this test fails and prints the new file; update it
//! with `SLITPATH_UPDATE_DIGESTS=1 cargo test --release --test determinism`, then run the browser
//! test, which must pass against the new values unchanged.
#![cfg(not(target_arch = "wasm32"))]

mod digest;

#[test]
fn conformal_digests_match_the_shared_file() {
    let lines: Vec<String> = digest::CASES.iter().map(|name| digest::digest_line(name)).collect();
    let wanted = lines.join("\n") + "\n";
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/digest/expected.txt");
    if std::env::var_os("SLITPATH_UPDATE_DIGESTS").is_some() {
        std::fs::write(&path, &wanted).expect("writes expected.txt");
        eprintln!("wrote {}:\n{wanted}", path.display());
        return;
    }
    let stale: Vec<&String> = digest::CASES
        .iter()
        .zip(&lines)
        .filter(|(name, l)| digest::expected_line(name) != Some(l.as_str()))
        .map(|(_, l)| l)
        .collect();
    assert!(
        stale.is_empty(),
        "conformal digests changed; if that is intended, run `SLITPATH_UPDATE_DIGESTS=1 cargo test --release --test determinism` \
         (new contents of tests/digest/expected.txt below), then the browser test\n{wanted}"
    );
}

/// The digest is sensitive to the last bit and to the order.
#[test]
fn digest_sees_one_ulp() {
    let a = [1.0, 2.0, 3.0];
    let b = [1.0, f64::from_bits(2.0f64.to_bits() + 1), 3.0];
    assert_ne!(digest::fnv1a(a), digest::fnv1a(b));
    assert_ne!(digest::fnv1a([1.0, 2.0]), digest::fnv1a([2.0, 1.0]));
    assert_ne!(digest::fnv1a([0.0]), digest::fnv1a([-0.0]));
}
