//! The numerical building blocks shared by the integrator, the models, the orbit solvers and the
//! continuation: one bracketing root finder ([`roots`]: Illinois regula falsi and bisection) and one
//! Newton iteration ([`newton`]); linear least squares by QR ([`least_squares`]) and a
//! Levenberg–Marquardt trust-region method ([`levenberg_marquardt`]), both on faer; sin and cos of
//! one argument with one reduction ([`trig`], the right-hand side's cost).

pub mod least_squares;
pub mod levenberg_marquardt;
pub mod newton;
pub mod roots;
pub mod trig;

pub use newton::{newton, Linearisation, NewtonOptions, NewtonSolution};
pub use roots::{Bisection, Illinois, Side};
