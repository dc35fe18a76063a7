//! Analytic test surfaces (one deterministic generator for every test, benchmark and sample).
