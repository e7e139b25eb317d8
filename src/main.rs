fn main() {
    std::process::exit(eyeshell_cli::main());
}

/// mimalloc, not glibc's malloc: it keeps a solve's freed buffers for the next one, where
/// glibc returned them to the kernel and faulted them back in (20 % of a warm solve at
/// N = 501; BENCHMARKS.md, "Beside the LU").
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;
