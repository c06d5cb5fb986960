// A test shared library that is not a plydem plug-in: no PLYDEM_PLUGIN symbols, which the loader
// refuses (ctest: cli_plugin_no_entry).
extern "C" __attribute__((visibility("default"))) int not_a_plydem_plugin() {
  return 1;
}
