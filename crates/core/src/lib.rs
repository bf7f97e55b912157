//! Shared vocabulary of colloidsim.
//!
//! Everything here is used by more than one method family: counter-based random streams
//! ([`rng`]), validated parameters and their errors ([`param`]), output folders and CSV/JSON
//! writers ([`output`]), the mean-square displacement of a running simulation ([`msd`]), memory
//! estimates checked before allocating ([`resources`]), sampling triggers ([`trigger`]),
//! messages between the domains of a run decomposed over ranks ([`exchange`]),
//! one-dimensional external fields ([`field1d`]) shared by Brownian cluster dynamics and the
//! exact 1D theory, Gauss–Legendre quadrature ([`quadrature`]), and the external tools tests check outputs with ([`tools`]).

pub mod exchange;
pub mod field1d;
pub mod msd;
pub mod output;
pub mod param;
pub mod quadrature;
pub mod resources;
pub mod rng;
pub mod timing;
pub mod tools;
pub mod trigger;

pub use param::ParamError;
