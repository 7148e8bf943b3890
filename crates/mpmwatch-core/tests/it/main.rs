//! Integration tests of mpmwatch-core: estimators against closed forms and scikit-learn, their properties, surrogates, the MI matrix, nominal models.
//! One test binary per crate, each test file a module, so the dependencies link once.

mod common;
mod detect;
mod estimator_properties;
mod estimators;
mod sim_model;
mod surrogates;
