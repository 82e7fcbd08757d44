//! The library: the models against references and their own properties, the readers and
//! writers, the solver on the NIST problems, fits of synthetic and stiff cases, a seeded
//! recovery run, and the pictures. Compiled into the library's unit tests (`cargo test --lib`), so they reach
//! what is private to the crate.

mod alta;
mod binary_fuzz;
mod fit;
mod fresnel_shadowing;
mod io;
mod kbs_reference;
mod merl;
mod model_props;
mod nist;
mod plot;
mod plot_sharp;
mod recover;
mod rgl;
mod stiff;
