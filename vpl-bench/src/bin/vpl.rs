//! `vpl`: render scenes, run the paper experiments, validate and benchmark,
//! with the toolkit's built-in samplers ([`vpl_bench::cli`]).

fn main() {
    vpl_bench::cli::main(&vpl_sampling::Registry::builtin())
}
