// Defaults of the sanitizer runtimes for test_sanitized (read before main; the environment's
// ASAN_OPTIONS / UBSAN_OPTIONS still override them): any report fails the test, with a stack.

extern "C" {
const char* __asan_default_options() { return "detect_leaks=1:abort_on_error=1"; }
const char* __ubsan_default_options() { return "print_stacktrace=1:halt_on_error=1"; }
}
