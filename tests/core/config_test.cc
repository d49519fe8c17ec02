#include "core/config.h"

#include <gtest/gtest.h>

#include "tests/test_util.h"

namespace foresight {
namespace {

struct Inner {
  double rate = 0.5;
  std::vector<int> widths = {4, 8};
  template <class A>
  void Serialize(A* a) {
    a->Visit("rate", &rate, config::Range::Open(0, 1), "a rate");
    a->Visit("widths", &widths, config::Range::AtLeast(1), "layer widths");
  }
};
enum class Kind { kA, kB };
struct Outer {
  int count = 3;
  std::string name = "x";
  bool flag = false;
  Kind kind = Kind::kA;
  Inner inner;
  template <class A>
  void Serialize(A* a) {
    a->Visit("count", &count, config::Range::AtLeast(1), "a count");
    a->Visit("name", &name, config::Range::Any(), "a name");
    a->Visit("flag", &flag, config::Range::Any(), "a flag");
    a->VisitEnum("kind", &kind, config::EnumNames<Kind>{{Kind::kA, "a"}, {Kind::kB, "b"}}, "a kind");
    a->Visit("inner", &inner, config::Range::Any(), "nested");
  }
};

Outer Parse(const std::string& text, const std::vector<std::string>& overrides = {}) {
  return config::FromYaml<Outer>(config::ParseYaml(text, "test.yaml"), "test.yaml", overrides);
}

TEST(Config, DefaultsAndValues) {
  const Outer d = Parse("{}");
  EXPECT_EQ(d.count, 3);
  EXPECT_EQ(d.inner.widths, (std::vector<int>{4, 8}));
  const Outer o = Parse("count: 7\nname: hi\nflag: true\nkind: b\ninner: {rate: 0.25, widths: [1, 2, 3]}\n");
  EXPECT_EQ(o.count, 7);
  EXPECT_EQ(o.name, "hi");
  EXPECT_TRUE(o.flag);
  EXPECT_EQ(o.kind, Kind::kB);
  EXPECT_DOUBLE_EQ(o.inner.rate, 0.25);
  EXPECT_EQ(o.inner.widths, (std::vector<int>{1, 2, 3}));
}

TEST(Config, UnknownKeyNamesFileLineAndPath) {
  testing::ExpectErrorContains([] { Parse("count: 2\ninner:\n  rat: 0.1\n"); },
                               {"test.yaml:3", "unknown key 'inner.rat'", "rate"});
}

TEST(Config, WrongTypeNamesPathValueAndExpectation) {
  testing::ExpectErrorContains([] { Parse("count: abc\n"); }, {"test.yaml:1", "'count'", "'abc'", "integer"});
  testing::ExpectErrorContains([] { Parse("count: 2.5\n"); }, {"'count'", "'2.5'"});
  testing::ExpectErrorContains([] { Parse("flag: maybe\n"); }, {"'flag'", "true or false"});
  testing::ExpectErrorContains([] { Parse("inner: 3\n"); }, {"'inner'", "mapping"});
  testing::ExpectErrorContains([] { Parse("inner: {widths: [1, x]}\n"); }, {"'inner.widths[1]'", "'x'"});
  testing::ExpectErrorContains([] { Parse("kind: c\n"); }, {"'kind'", "'a'", "'b'"});
  testing::ExpectErrorContains([] { Parse("inner: {rate: nan}\n"); }, {"'inner.rate'", "finite"});
}

TEST(Config, OutOfRangeNamesTheRange) {
  testing::ExpectErrorContains([] { Parse("count: 0\n"); }, {"'count'", "'0'", ">= 1"});
  testing::ExpectErrorContains([] { Parse("inner: {rate: 1.0}\n"); }, {"'inner.rate'", "in (0, 1)"});
  testing::ExpectErrorContains([] { Parse("inner: {widths: [0]}\n"); }, {"'inner.widths[0]'"});
}

TEST(Config, OverridesUseThePathSyntax) {
  const Outer o = Parse("count: 2\n", {"inner.rate=0.75", "count=9", "inner.widths=[5, 6]", "name=abc"});
  EXPECT_EQ(o.count, 9);
  EXPECT_DOUBLE_EQ(o.inner.rate, 0.75);
  EXPECT_EQ(o.inner.widths, (std::vector<int>{5, 6}));
  EXPECT_EQ(o.name, "abc");
  testing::ExpectErrorContains([] { Parse("{}", {"inner.nope=1"}); }, {"unknown key 'inner.nope'"});
  testing::ExpectErrorContains([] { Parse("{}", {"novalue"}); }, {"key.path=value"});
  testing::ExpectErrorContains([] { Parse("{}", {"count.x=1"}); }, {"'count'", "mapping"});
  testing::ExpectErrorContains([] { Parse("count: 2\n", {"count.x=1"}); }, {"'count' is not a mapping"});
}

TEST(Config, WriteReadRoundTrip) {
  Outer o = Parse("count: 5\nname: 'a b: c'\nkind: b\ninner: {rate: 0.1, widths: [7]}\n");
  const std::string text = config::ToYaml(o);
  const Outer back = config::FromYaml<Outer>(config::ParseYaml(text, "round"), "round");
  EXPECT_EQ(config::ToYaml(back), text);
  EXPECT_EQ(back.name, "a b: c");
  EXPECT_DOUBLE_EQ(back.inner.rate, 0.1);
}

TEST(Config, ReferenceListsEveryKeyWithDefault) {
  const std::string table = config::ReferenceTable<Outer>();
  for (const char* key : {"`count`", "`name`", "`flag`", "`kind`", "`inner.rate`", "`inner.widths`"})
    EXPECT_NE(table.find(key), std::string::npos) << key;
  EXPECT_NE(table.find("a | b"), std::string::npos);
  EXPECT_NE(table.find("`0.5`"), std::string::npos);
}

TEST(Config, InvalidYamlNamesTheFile) {
  testing::ExpectErrorContains([] { config::ParseYaml("a: [1, 2", "bad.yaml"); }, {"bad.yaml", "invalid YAML"});
  testing::ExpectErrorContains([] { config::LoadYamlFile("/nonexistent/x.yaml"); }, {"/nonexistent/x.yaml"});
}

}  // namespace
}  // namespace foresight
