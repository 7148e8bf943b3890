//! One module per command-line verb; each parses its own arguments and calls the library.

pub mod analyze;
pub mod bench;
pub mod casebook;
pub mod demo;
pub mod diagnose;
pub mod loadgen;
pub mod mi;
pub mod reproduce;
pub mod serve;
pub mod simulate;

/// A clap parser for a core enum named by `strum`: the help lists the names and a wrong one is
/// refused with them, without the core crate depending on clap.
pub(crate) fn choice<T>() -> impl clap::builder::TypedValueParser<Value = T>
where
    T: strum::VariantNames + std::str::FromStr + Clone + Send + Sync + 'static,
    <T as std::str::FromStr>::Err: std::error::Error + Send + Sync + 'static,
{
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(T::VARIANTS).try_map(|s| s.parse::<T>())
}
