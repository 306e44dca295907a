//! One logging layer: `defmt` on the chip, the `log` facade on the host, so
//! host builds never link defmt. Format strings use only `{}` so both accept them.

#[cfg(target_os = "none")]
#[doc(hidden)]
pub use defmt as backend;
#[cfg(not(target_os = "none"))]
#[doc(hidden)]
pub use log as backend;

#[macro_export]
macro_rules! info {
    ($($t:tt)*) => { $crate::log::backend::info!($($t)*) };
}

#[macro_export]
macro_rules! warn {
    ($($t:tt)*) => { $crate::log::backend::warn!($($t)*) };
}

#[macro_export]
macro_rules! debug {
    ($($t:tt)*) => { $crate::log::backend::debug!($($t)*) };
}
