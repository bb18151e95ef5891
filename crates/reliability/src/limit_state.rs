//! The caller's limit-state function g(x) in physical space; failure is g ≤ 0.
//!
//! Plain closures `FnMut(&[f64]) -> f64` are limit states (FORM then takes central finite
//! differences). [`WithGradient`] wraps a closure that also fills ∂g/∂x; [`Fallible`] one that
//! returns a `Result` (an FE solve that can fail); [`WithHessian`] one that also fills the
//! Hessian (SORM). Implement [`LimitState`] directly for more.

use crate::error::EvalError;

/// g(x), and optionally its gradient.
pub trait LimitState {
    /// g(x).
    fn value(&mut self, x: &[f64]) -> Result<f64, EvalError>;

    /// g(x) with ∂g/∂x written to `grad`, or `Ok(None)` when no gradient is available (the
    /// default; FORM then uses central differences).
    fn value_and_gradient(
        &mut self,
        _x: &[f64],
        _grad: &mut [f64],
    ) -> Result<Option<f64>, EvalError> {
        Ok(None)
    }

    /// g(x) with ∂g/∂x written to `grad` and the Hessian ∂²g/∂xᵢ∂xⱼ to `hess` (n×n, row-major),
    /// or `Ok(None)` when the limit state cannot give it cheaply (the default; SORM then takes
    /// central differences in standard normal space, see [`crate::sorm`]).
    fn value_gradient_hessian(
        &mut self,
        _x: &[f64],
        _grad: &mut [f64],
        _hess: &mut [f64],
    ) -> Result<Option<f64>, EvalError> {
        Ok(None)
    }
}

impl<F: FnMut(&[f64]) -> f64> LimitState for F {
    fn value(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        Ok(self(x))
    }
}

/// A closure `|x, grad| -> g` that returns g(x) and fills ∂g/∂x.
pub struct WithGradient<F>(pub F);

impl<F: FnMut(&[f64], &mut [f64]) -> f64> LimitState for WithGradient<F> {
    fn value(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        let mut scratch = vec![0.0; x.len()];
        Ok((self.0)(x, &mut scratch))
    }

    fn value_and_gradient(
        &mut self,
        x: &[f64],
        grad: &mut [f64],
    ) -> Result<Option<f64>, EvalError> {
        Ok(Some((self.0)(x, grad)))
    }
}

/// A closure `|x| -> Result<g, EvalError>` whose evaluation can fail.
pub struct Fallible<F>(pub F);

impl<F: FnMut(&[f64]) -> Result<f64, EvalError>> LimitState for Fallible<F> {
    fn value(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        (self.0)(x)
    }
}

/// A closure `|x, grad, hess| -> g` that returns g(x), fills ∂g/∂x and the Hessian ∂²g/∂xᵢ∂xⱼ
/// (n×n, row-major).
pub struct WithHessian<F>(pub F);

impl<F: FnMut(&[f64], &mut [f64], &mut [f64]) -> f64> LimitState for WithHessian<F> {
    fn value(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        let n = x.len();
        Ok((self.0)(x, &mut vec![0.0; n], &mut vec![0.0; n * n]))
    }

    fn value_and_gradient(
        &mut self,
        x: &[f64],
        grad: &mut [f64],
    ) -> Result<Option<f64>, EvalError> {
        let n = x.len();
        Ok(Some((self.0)(x, grad, &mut vec![0.0; n * n])))
    }

    fn value_gradient_hessian(
        &mut self,
        x: &[f64],
        grad: &mut [f64],
        hess: &mut [f64],
    ) -> Result<Option<f64>, EvalError> {
        Ok(Some((self.0)(x, grad, hess)))
    }
}
