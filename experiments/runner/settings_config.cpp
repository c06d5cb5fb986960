#include "experiments/runner/settings_config.hpp"

namespace plydem {

SettingValue config_edge_value(const ExperimentConfig& config, const SettingInfo& info,
                               const std::string& key) {
  switch (info.type) {
    case SettingType::kSwitch:
      return config.boolean(key, false);
    case SettingType::kInteger:
      return config.integer(key, 0);
    case SettingType::kNumber:
      return config.number(key, 0);
    case SettingType::kText:
      return config.string(key, "");
    case SettingType::kTexts:
      return config.strings(key, {});
  }
  return std::monostate{};
}

}  // namespace plydem
