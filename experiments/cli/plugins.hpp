#pragma once
/// \file
/// The command line's plug-ins: `plydem --plugin FILE ...` (repeatable) and PLYDEM_PLUGIN_PATH
/// load code that registers strategies and experiment kinds before the command runs, chosen by
/// the file's extension:
///   FILE.py          a Python file, run in the embedded interpreter (python_plugin.hpp);
///   libNAME.so[.N]   a C++ shared library built with PLYDEM_PLUGIN
///   (experiments/runner/plugin.hpp).
/// PLYDEM_PLUGIN_PATH (colon-separated files or folders; a folder's NAME.so files in name order)
/// is loaded first, then each --plugin in the order given.
#include <string>
#include <vector>

namespace plydem::cli {

/// Loads the plug-ins of PLYDEM_PLUGIN_PATH, then `files`, into the program's registries. Throws
/// plydem::Error naming the file and why it was refused (experiments/runner/plugin.hpp,
/// python_plugin.hpp), or a file that is neither FILE.py nor a shared library.
void load_plugins(const std::vector<std::string>& files);

}  // namespace plydem::cli
