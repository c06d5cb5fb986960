// A test shared library that calls a function no one defines: the dynamic linker cannot load it,
// and the loader says so with the symbol's name (ctest: cli_plugin_undefined_symbol).
extern "C" void plydem_function_nobody_defines();

extern "C" __attribute__((visibility("default"))) void plydem_plugin_calls_nobody() {
  plydem_function_nobody_defines();
}
