//! The wasm-bindgen facade (filled by the web branch).
