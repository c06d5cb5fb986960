#include "experiments/runner/experiment.hpp"
#include "tests/fuzz/fuzz_inputs.hpp"

namespace plydem::fuzz {

void experiment_config(std::string_view input) {
  refused_or_accepted([&] {
    const ExperimentConfig c = ExperimentConfig::parse(std::string(input), "fuzz.toml");
    refused_or_accepted([&] { (void)c.kind(); });
    refused_or_accepted([&] { (void)c.description(); });
    refused_or_accepted([&] { (void)c.name(); });
    refused_or_accepted([&] {
      c.require_known_keys({"experiment", "description", "material", "layup", "coupon", "quick"});
    });
    // The getters of the keys the kinds read, each type.
    for (const char* key : {"material", "layup", "strategy", "coupon.grips", "experiment"}) {
      refused_or_accepted([&] { (void)c.string(key, ""); });
    }
    for (const char* key :
         {"coupon.length_mm", "quick.width_mm", "interface.normal", "angle_deg"}) {
      refused_or_accepted([&] { (void)c.number(key, 0); });
    }
    for (const char* key : {"seed", "events.max_events", "explicit.cycles"}) {
      refused_or_accepted([&] { (void)c.integer(key, 1); });
    }
    for (const char* key : {"softening", "output.vtu_series"}) {
      refused_or_accepted([&] { (void)c.boolean(key, false); });
    }
    refused_or_accepted([&] { (void)c.strings("strategy_options", {}); });
    refused_or_accepted([&] { (void)c.strings("strategies", {"hex2d"}); });
    refused_or_accepted([&] { (void)c.numbers("angles_deg", {}); });
    refused_or_accepted([&] { (void)c.contains("coupon"); });
  });
}

}  // namespace plydem::fuzz
