//! `vpl`: render scenes, run the paper experiments, validate and benchmark,
//! with the toolkit's built-in samplers ([`vpl_cli`]).

fn main() {
    vpl_cli::main(&vpl_sampling::Registry::builtin())
}
