// docs/config_reference.md is generated: it must match what the code generates now.

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "training/kinds.h"
#include "training/navigation/config.h"
#include "training/occupancy/config.h"
#include "training/span/config.h"

namespace foresight {
namespace {

TEST(Docs, ConfigReferenceIsCurrent) {
  const char* src = std::getenv("FORESIGHT_SOURCE_DIR");
  ASSERT_NE(src, nullptr);
  std::ifstream in(std::string(src) + "/docs/config_reference.md");
  ASSERT_TRUE(in.good()) << "docs/config_reference.md missing: run `foresight docs config -o "
                            "docs/config_reference.md`";
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), BuiltinKinds().ReferenceMarkdown())
      << "docs/config_reference.md is stale: run `build/bin/foresight docs config -o "
         "docs/config_reference.md`";
}

TEST(Docs, ShippedNavigationConfigsLoad) {
  const std::string src = std::getenv("FORESIGHT_SOURCE_DIR");
  for (const char* name : {"sim1", "sim2", "dataset"}) {
    const nav::ExperimentConfig c = config::LoadExperimentConfig<nav::ExperimentConfig>(
        src + "/configs/navigation/" + name + ".yaml");
    EXPECT_EQ(c.scenario.name, name);
    EXPECT_EQ(c.methods.size(), 4u);
    EXPECT_TRUE(c.Uses(nav::Method::kOrca)) << name;
    EXPECT_GE(c.episodes, 20);
  }
  for (const char* name : {"predictor", "predictor_thor"})
    EXPECT_NO_THROW(config::LoadExperimentConfig<span::ExperimentConfig>(
        src + "/configs/navigation/" + name + ".yaml", {}))
        << name;
}

TEST(Docs, ShippedConfigsLoad) {
  const std::string src = std::getenv("FORESIGHT_SOURCE_DIR");
  for (const char* name : {"quickstart", "span/eth_ucy_eth", "span/eth_ucy_hotel",
                           "span/eth_ucy_univ", "span/eth_ucy_zara1"})
    EXPECT_NO_THROW(config::LoadExperimentConfig<span::ExperimentConfig>(
        src + "/configs/" + name + ".yaml", {}))
        << name;
  for (const char* name : {"intel", "intel_fusion", "synthetic", "synthetic_fusion"})
    EXPECT_NO_THROW(config::LoadExperimentConfig<occupancy::ExperimentConfig>(
        src + "/configs/occupancy/" + name + ".yaml", {}))
        << name;
}

}  // namespace
}  // namespace foresight
