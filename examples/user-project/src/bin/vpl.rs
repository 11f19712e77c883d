//! The toolkit's `vpl` command with this project's samplers in its registry.

fn main() {
    vpl_cli::main(&my_vpl_experiment::registry())
}
