fn main() {
    std::process::exit(eyeshell::cli::main());
}
