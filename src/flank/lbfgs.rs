//! A small limited-memory BFGS minimiser (Nocedal & Wright, Algorithm 7.4) with a backtracking
//! Armijo line search, for the inner loop of the flank optimisation.
//!
//! Deterministic (plain `+ − × ÷ sqrt`, fixed loop order): the same start gives the same bits on
//! every target. A pair (s, y) whose curvature s·y is not positive is skipped, so the implicit
//! inverse Hessian stays positive definite and every direction is a descent direction. The
//! first step moves no unknown further than `first_step`; later ones start from the unit step
//! of the quasi-Newton direction (scaled by s·y / y·y, eq. 7.20).
//!
//! Stops when the gradient's largest entry is at most `gtol`, when a step moves no unknown
//! more than `xtol`, when F no longer decreases by more than `ftol`·|F|, when the line search
//! cannot decrease F (a minimum to rounding), or after `max_iterations`.

/// Options of [`minimise`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LbfgsOptions {
    /// Pairs (s, y) kept.
    pub history: usize,
    pub max_iterations: usize,
    /// Largest gradient entry at convergence.
    pub gtol: f64,
    /// Largest move of an unknown in a step at convergence.
    pub xtol: f64,
    /// Relative decrease of F at convergence.
    pub ftol: f64,
    /// Largest move of an unknown in the first step.
    pub first_step: f64,
}

/// Why [`minimise`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Stop {
    Gradient,
    Step,
    Decrease,
    LineSearch,
    Iterations,
}

/// What [`minimise`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LbfgsResult {
    pub f: f64,
    pub iterations: usize,
    pub evaluations: usize,
    pub stop: Stop,
}

/// Minimises `f` from `x` (overwritten with the minimiser). `f(x, grad)` returns F and writes
/// its gradient. A non-finite F or gradient at the start is returned as is (the caller checks).
pub fn minimise(x: &mut [f64], mut f: impl FnMut(&[f64], &mut [f64]) -> f64, o: &LbfgsOptions) -> LbfgsResult {
    let n = x.len();
    let mut g = vec![0.0; n];
    let mut fx = f(x, &mut g);
    let mut evaluations = 1;
    let mut s_hist: Vec<Vec<f64>> = Vec::new();
    let mut y_hist: Vec<Vec<f64>> = Vec::new();
    let mut rho: Vec<f64> = Vec::new();
    let (mut trial, mut g_trial, mut dir) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut alpha_hist = vec![0.0; o.history];
    let done = |stop, fx, iterations, evaluations| LbfgsResult { f: fx, iterations, evaluations, stop };
    for iteration in 0..o.max_iterations {
        if !fx.is_finite() || max_abs(&g) <= o.gtol {
            return done(Stop::Gradient, fx, iteration, evaluations);
        }
        // Two-loop recursion: dir = −H g.
        dir.copy_from_slice(&g);
        let m = s_hist.len();
        for k in (0..m).rev() {
            let a = rho[k] * dot(&s_hist[k], &dir);
            alpha_hist[k] = a;
            axpy(-a, &y_hist[k], &mut dir);
        }
        if m > 0 {
            let gamma = dot(&s_hist[m - 1], &y_hist[m - 1]) / dot(&y_hist[m - 1], &y_hist[m - 1]);
            dir.iter_mut().for_each(|v| *v *= gamma);
        }
        for k in 0..m {
            let b = rho[k] * dot(&y_hist[k], &dir);
            axpy(alpha_hist[k] - b, &s_hist[k], &mut dir);
        }
        dir.iter_mut().for_each(|v| *v = -*v);
        let mut slope = dot(&g, &dir);
        if !(slope < 0.0) {
            // Not a descent direction (rounding): restart from steepest descent.
            s_hist.clear();
            y_hist.clear();
            rho.clear();
            dir.iter_mut().zip(&g).for_each(|(d, gi)| *d = -gi);
            slope = dot(&g, &dir);
        }
        let mut alpha = if s_hist.is_empty() { (o.first_step / max_abs(&dir)).min(1.0) } else { 1.0 };
        // Backtracking Armijo search.
        let mut accepted = None;
        for _ in 0..60 {
            for i in 0..n {
                trial[i] = x[i] + alpha * dir[i];
            }
            let ft = f(&trial, &mut g_trial);
            evaluations += 1;
            if ft.is_finite() && ft <= fx + 1e-4 * alpha * slope {
                accepted = Some(ft);
                break;
            }
            alpha *= if ft.is_finite() { 0.5 } else { 0.1 };
        }
        let Some(ft) = accepted else {
            return done(Stop::LineSearch, fx, iteration, evaluations);
        };
        let step = alpha * max_abs(&dir);
        let decrease = fx - ft;
        let s: Vec<f64> = (0..n).map(|i| trial[i] - x[i]).collect();
        let y: Vec<f64> = (0..n).map(|i| g_trial[i] - g[i]).collect();
        x.copy_from_slice(&trial);
        g.copy_from_slice(&g_trial);
        fx = ft;
        let sy = dot(&s, &y);
        if sy > 1e-300 {
            if s_hist.len() == o.history {
                s_hist.remove(0);
                y_hist.remove(0);
                rho.remove(0);
            }
            rho.push(1.0 / sy);
            s_hist.push(s);
            y_hist.push(y);
        }
        if step <= o.xtol {
            return done(Stop::Step, fx, iteration + 1, evaluations);
        }
        if decrease <= o.ftol * fx.abs() {
            return done(Stop::Decrease, fx, iteration + 1, evaluations);
        }
    }
    let stop = if max_abs(&g) <= o.gtol { Stop::Gradient } else { Stop::Iterations };
    done(stop, fx, o.max_iterations, evaluations)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    y.iter_mut().zip(x).for_each(|(yi, xi)| *yi += a * xi);
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minimises_the_rosenbrock_function() {
        let mut x = vec![-1.2, 1.0, -1.2, 1.0];
        let rosen = |x: &[f64], g: &mut [f64]| {
            let mut f = 0.0;
            g.iter_mut().for_each(|v| *v = 0.0);
            for i in 0..x.len() - 1 {
                let (a, b) = (1.0 - x[i], x[i + 1] - x[i] * x[i]);
                f += a * a + 100.0 * b * b;
                g[i] += -2.0 * a - 400.0 * x[i] * b;
                g[i + 1] += 200.0 * b;
            }
            f
        };
        let o = LbfgsOptions { history: 8, max_iterations: 500, gtol: 1e-10, xtol: 0.0, ftol: 0.0, first_step: 0.1 };
        let r = minimise(&mut x, rosen, &o);
        assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-8), "{x:?} after {r:?}");
    }

    #[test]
    fn a_zero_gradient_moves_nothing() {
        let mut x = vec![3.0, -2.0];
        let o = LbfgsOptions { history: 5, max_iterations: 10, gtol: 0.0, xtol: 0.0, ftol: 0.0, first_step: 1.0 };
        let r = minimise(
            &mut x,
            |_, g| {
                g.iter_mut().for_each(|v| *v = 0.0);
                1.0
            },
            &o,
        );
        assert_eq!(x, vec![3.0, -2.0]);
        assert_eq!(r.stop, Stop::Gradient);
    }
}
