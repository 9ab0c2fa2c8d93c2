fn main() -> std::process::ExitCode {
    raypipe::commands::main()
}
