//! The conformal benchmark in headless Chromium, the wasm twin of `cargo bench --bench conformal`
//! (same cases from `slitpath::bench`). Run by `npm run bench`; not part of `npm test`.
#![cfg(target_arch = "wasm32")]

use slitpath::bench::{best_mesh, conformal_cases, format_mesh, format_row, mesh_sheet, run_conformal, TABLE_HEADER};
use slitpath::mesh::stl;
use wasm_bindgen::JsCast;
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

/// Returns to the browser's event loop for a moment. The cases run synchronously in the page, and
/// ChromeDriver gives up on a renderer that has not answered for 30 s ("Timed out receiving
/// message from renderer"): the whole pipeline's cases take longer than that together.
async fn yield_to_browser() {
    let promise = js_sys::Promise::new(&mut |resolve, _| {
        web_sys::window().expect("a window").set_timeout_with_callback(&resolve).expect("setTimeout");
    });
    wasm_bindgen_futures::JsFuture::from(promise).await.expect("a resolved timeout");
}

#[wasm_bindgen_test]
fn mesh_stage_in_the_browser() {
    let performance = web_sys::window().expect("a window").performance().expect("performance");
    let now = || performance.now();
    let bytes = stl::write_binary(&mesh_sheet(730), "bench sheet");
    let best = best_mesh(&bytes, 3, &now).expect("valid mesh");
    console_log!("wasm (headless Chromium), best of 3: {}", format_mesh(&best));
}

#[wasm_bindgen_test]
async fn conformal_core_in_the_browser() {
    let performance = web_sys::window().expect("a window").performance().expect("performance");
    let now = || performance.now();
    console_log!("conformal core, wasm (headless Chromium)\n{TABLE_HEADER}");
    for (name, mesh) in conformal_cases() {
        yield_to_browser().await;
        // Best of 3, as natively.
        let best = (0..3)
            .map(|_| run_conformal(&name, &mesh, &now).expect("plannable"))
            .min_by(|a, b| {
                (a.slitmap_pole_ms + a.flatten_factorise_ms).total_cmp(&(b.slitmap_pole_ms + b.flatten_factorise_ms))
            })
            .expect("three runs");
        console_log!("{}", format_row(&best));
    }
}

#[wasm_bindgen_test]
async fn whole_pipeline_in_the_browser() {
    let performance = web_sys::window().expect("a window").performance().expect("performance");
    let now = || performance.now();
    console_log!("whole pipeline, wasm (headless Chromium)\n{}", slitpath::bench::PLAN_HEADER);
    for (name, mesh) in slitpath::bench::plan_cases("") {
        yield_to_browser().await;
        match slitpath::bench::run_plan(&name, &mesh, &now) {
            Ok(row) => console_log!("{row}"),
            Err(e) => console_log!("{name} cannot be planned: {e}"),
        }
    }
    // Linear memory never shrinks: its size now is the peak over every case (issue 5: ≤ 1 GiB).
    let memory: js_sys::WebAssembly::Memory = wasm_bindgen::memory().unchecked_into();
    let bytes = js_sys::ArrayBuffer::from(memory.buffer()).byte_length();
    console_log!("wasm linear memory after all cases (its peak): {:.0} MiB", bytes as f64 / (1024.0 * 1024.0));
}

#[wasm_bindgen_test]
async fn path_length_in_the_browser() {
    // The first parts of `cargo bench --bench length`'s list (the whole list takes minutes).
    let performance = web_sys::window().expect("a window").performance().expect("performance");
    let now = || performance.now();
    console_log!("path length at equal finish, wasm (headless Chromium)\n{}", slitpath::bench::LENGTH_HEADER);
    let (mut rows, mut failed) = (Vec::new(), 0);
    for part in slitpath::bench::length_parts(6) {
        yield_to_browser().await;
        match slitpath::bench::run_length(&part, &now) {
            Ok(row) => {
                console_log!("{}", slitpath::bench::format_length(&row));
                rows.push(row);
            }
            Err(e) => {
                console_log!("{:<42} cannot be planned: {e}", part.name);
                failed += 1;
            }
        }
    }
    console_log!("{}", slitpath::bench::summarise_lengths(&rows, failed));
}

#[wasm_bindgen_test]
async fn flank_in_the_browser() {
    let performance = web_sys::window().expect("a window").performance().expect("performance");
    let now = || performance.now();
    yield_to_browser().await;
    match slitpath::bench::run_flank(&now) {
        Ok(f) => console_log!("wasm (headless Chromium): {}", slitpath::bench::format_flank(&f)),
        Err(e) => console_log!("the flank case cannot be planned: {e}"),
    }
}

#[wasm_bindgen_test]
async fn step_in_the_browser() {
    use slitpath::bench::step::{format_step, run_coons_band, run_step, step_cases};
    let performance = web_sys::window().expect("a window").performance().expect("performance");
    let now = || performance.now();
    for (name, text) in step_cases() {
        yield_to_browser().await;
        match run_step(name, &text, 3, &now) {
            Ok(f) => console_log!("wasm (headless Chromium), best of 3: {}", format_step(&f)),
            Err(e) => console_log!("{name} cannot be read: {e}"),
        }
    }
    yield_to_browser().await;
    match run_coons_band(&now) {
        Ok(row) => console_log!("wasm (headless Chromium): {row}"),
        Err(e) => console_log!("the blade band cannot be planned: {e}"),
    }
}
