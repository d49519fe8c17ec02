#include "core/json.h"

#include <gtest/gtest.h>

#include <cmath>

namespace foresight {
namespace {

TEST(Json, OrderedNestedEscapedAndNullForNonFinite) {
  JsonObject inner;
  inner.Set("b", 2).Set("a", 0.5);
  JsonObject o;
  o.Set("name", "x\"y\n").Set("nan", std::nan("")).Set("inf", INFINITY).Set("ok", true);
  o.Set("inner", inner).Set("list", std::vector<double>{1.0, NAN});
  EXPECT_EQ(o.Dump(),
            "{\n  \"name\": \"x\\\"y\\n\",\n  \"nan\": null,\n  \"inf\": null,\n  \"ok\": true,\n"
            "  \"inner\": {\n    \"b\": 2,\n    \"a\": 0.5\n  },\n  \"list\": [1, null]\n}");
}

TEST(Json, SettingAKeyAgainReplacesItInPlace) {
  JsonObject o;
  o.Set("a", 1).Set("b", 2).Set("a", 3);
  EXPECT_EQ(o.Dump(), "{\n  \"a\": 3,\n  \"b\": 2\n}");
  EXPECT_EQ(JsonObject().Dump(), "{}");
  EXPECT_EQ(JsonNumber(0.1), "0.1");
  EXPECT_EQ(JsonNumber(-1e-12), "-1e-12");
}

}  // namespace
}  // namespace foresight
