// A test plug-in built "against another plydem": its version symbol names one that is not this
// build's, which the loader refuses before calling anything (ctest: cli_plugin_other_version).
namespace plydem {
struct PluginRegistries;
}

extern "C" __attribute__((visibility("default"))) const char plydem_plugin_version[] =
    "0.0.0-other";
extern "C" __attribute__((visibility("default"))) void plydem_plugin_register(
    plydem::PluginRegistries&) {}
