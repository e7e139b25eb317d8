fn main() {
    std::process::exit(eyeshell_cli::main());
}
