#include "core/config.h"

#include <gtest/gtest.h>

#include "core/layer_widths.h"
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
    a->VisitEnum("kind", &kind, config::EnumNames<Kind>{{Kind::kA, "a"}, {Kind::kB, "b"}},
                 "a kind");
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
  const Outer o =
      Parse("count: 7\nname: hi\nflag: true\nkind: b\ninner: {rate: 0.25, widths: [1, 2, 3]}\n");
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
  testing::ExpectErrorContains([] { Parse("count: abc\n"); },
                               {"test.yaml:1", "'count'", "'abc'", "integer"});
  testing::ExpectErrorContains([] { Parse("count: 2.5\n"); }, {"'count'", "'2.5'"});
  testing::ExpectErrorContains([] { Parse("flag: maybe\n"); }, {"'flag'", "true or false"});
  testing::ExpectErrorContains([] { Parse("inner: 3\n"); }, {"'inner'", "mapping"});
  testing::ExpectErrorContains([] { Parse("inner: {widths: [1, x]}\n"); },
                               {"'inner.widths[1]'", "'x'"});
  testing::ExpectErrorContains([] { Parse("kind: c\n"); }, {"'kind'", "'a'", "'b'"});
  testing::ExpectErrorContains([] { Parse("inner: {rate: nan}\n"); }, {"'inner.rate'", "finite"});
}

TEST(Config, OutOfRangeNamesTheRange) {
  testing::ExpectErrorContains([] { Parse("count: 0\n"); }, {"'count'", "'0'", ">= 1"});
  testing::ExpectErrorContains([] { Parse("inner: {rate: 1.0}\n"); },
                               {"'inner.rate'", "in (0, 1)"});
  testing::ExpectErrorContains([] { Parse("inner: {widths: [0]}\n"); }, {"'inner.widths[0]'"});
}

TEST(Config, OverridesUseThePathSyntax) {
  const Outer o =
      Parse("count: 2\n", {"inner.rate=0.75", "count=9", "inner.widths=[5, 6]", "name=abc"});
  EXPECT_EQ(o.count, 9);
  EXPECT_DOUBLE_EQ(o.inner.rate, 0.75);
  EXPECT_EQ(o.inner.widths, (std::vector<int>{5, 6}));
  EXPECT_EQ(o.name, "abc");
  testing::ExpectErrorContains([] { Parse("{}", {"inner.nope=1"}); }, {"unknown key 'inner.nope'"});
  testing::ExpectErrorContains([] { Parse("{}", {"novalue"}); }, {"key.path=value"});
  testing::ExpectErrorContains([] { Parse("{}", {"count.x=1"}); }, {"'count'", "mapping"});
  testing::ExpectErrorContains([] { Parse("count: 2\n", {"count.x=1"}); },
                               {"'count' is not a mapping"});
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
  for (const char* key :
       {"`count`", "`name`", "`flag`", "`kind`", "`inner.rate`", "`inner.widths`"})
    EXPECT_NE(table.find(key), std::string::npos) << key;
  // Enum choices, with the '|' escaped so the Markdown table keeps its columns.
  EXPECT_NE(table.find("a \\| b"), std::string::npos);
  EXPECT_NE(table.find("`0.5`"), std::string::npos);
}

// Issue 18, defect 5: yaml-cpp answers a repeated key with its first value; refuse it instead.
TEST(Config, RepeatedKeysAreRefusedWithBothLines) {
  testing::ExpectErrorContains([] { Parse("count: 2\nname: a\ncount: 5\n"); },
                               {"test.yaml:3", "key 'count' is repeated", "first at line 1"});
  testing::ExpectErrorContains([] { Parse("inner:\n  rate: 0.1\n  rate: 0.2\n"); },
                               {"test.yaml:3", "'rate'", "line 2"});
  testing::ExpectErrorContains([] { Parse("inner: {widths: [1], widths: [2]}\n"); },
                               {"'widths' is repeated"});
}

// Issue 18, defect 6 and 7: an empty config file does not silently train defaults, and a huge one
// is refused before it is parsed.
TEST(Config, EmptyAndHugeConfigFilesAreRefused) {
  testing::TempDir dir;
  testing::WriteText(dir.File("empty.yaml"), "# nothing but a comment\n");
  testing::ExpectErrorContains([&] { config::LoadYamlFile(dir.File("empty.yaml")); },
                               {"empty.yaml", "empty"});
  testing::WriteText(dir.File("huge.yaml"), "widths: [" + std::string(2 << 20, '1') + "]\n");
  testing::ExpectErrorContains([&] { config::LoadYamlFile(dir.File("huge.yaml")); },
                               {"huge.yaml", "bytes; at most"});
  testing::ExpectErrorContains([&] { config::LoadYamlFile(dir.File("none.yaml")); },
                               {"none.yaml", "cannot open"});
}

TEST(Config, InvalidYamlNamesTheFile) {
  testing::ExpectErrorContains([] { config::ParseYaml("a: [1, 2", "bad.yaml"); },
                               {"bad.yaml", "invalid YAML"});
  testing::ExpectErrorContains([] { config::LoadYamlFile("/nonexistent/x.yaml"); },
                               {"/nonexistent/x.yaml"});
}

// std::vector<S> of config structs: a YAML sequence of mappings.
struct Segment {
  double x0 = 0, x1 = 1;
  std::vector<double> box = {0, 1};
  template <class A>
  void Serialize(A* a) {
    a->Visit("x0", &x0, config::Range::Any(), "start");
    a->Visit("x1", &x1, config::Range::NonNegative(), "end");
    a->Visit("box", &box, config::Range::Any(), "a box");
  }
};
struct Scene {
  std::string name = "s";
  std::vector<Segment> segments = {Segment{}, Segment{2, 3, {4}}};
  Inner inner;
  template <class A>
  void Serialize(A* a) {
    a->Visit("name", &name, config::Range::Any(), "a name");
    a->Visit("segments", &segments, config::Range::Any(), "wall segments");
    a->Visit("inner", &inner, config::Range::Any(), "nested");
  }
};

Scene ParseScene(const std::string& text) {
  return config::FromYaml<Scene>(config::ParseYaml(text, "scene.yaml"), "scene.yaml");
}

TEST(Config, VectorOfStructsReadsEachElementWithDefaults) {
  const Scene d = ParseScene("{}");
  ASSERT_EQ(d.segments.size(), 2u);
  EXPECT_DOUBLE_EQ(d.segments[1].x1, 3);
  const Scene s =
      ParseScene("segments:\n  - {x0: -1.5, x1: 2}\n  - x1: 4\n    box: [1, 2, 3]\n  - {}\n");
  ASSERT_EQ(s.segments.size(), 3u);
  EXPECT_DOUBLE_EQ(s.segments[0].x0, -1.5);
  EXPECT_DOUBLE_EQ(s.segments[0].x1, 2);
  EXPECT_EQ(s.segments[0].box, (std::vector<double>{0, 1}));  // element defaults, not the list's
  EXPECT_DOUBLE_EQ(s.segments[1].x0, 0);
  EXPECT_EQ(s.segments[1].box, (std::vector<double>{1, 2, 3}));
  EXPECT_DOUBLE_EQ(s.segments[2].x1, 1);
  EXPECT_TRUE(ParseScene("segments: []\n").segments.empty());
}

TEST(Config, VectorOfStructsErrorsNameTheElementPath) {
  testing::ExpectErrorContains([] { ParseScene("segments:\n  - {x0: 1}\n  - {x0: 1, y0: 2}\n"); },
                               {"scene.yaml:3", "unknown key 'segments[1].y0'", "x0"});
  testing::ExpectErrorContains([] { ParseScene("segments:\n  - {x1: -1}\n"); },
                               {"scene.yaml:2", "'segments[0].x1'", "'-1'", ">= 0"});
  testing::ExpectErrorContains([] { ParseScene("segments:\n  - {}\n  - {box: [1, a]}\n"); },
                               {"'segments[1].box[1]'", "'a'"});
  testing::ExpectErrorContains([] { ParseScene("segments: {x0: 1}\n"); },
                               {"'segments'", "a list of mappings"});
  testing::ExpectErrorContains([] { ParseScene("segments: [3]\n"); },
                               {"'segments[0]'", "'3'", "a mapping"});
}

TEST(Config, OverridesReachListElements) {
  const std::string text = "segments:\n  - {x0: 1}\n  - {x0: 2}\n";
  const Scene s = config::FromYaml<Scene>(config::ParseYaml(text, "s.yaml"), "s.yaml",
                                          {"segments[1].x1=9", "segments[0].box=[3, 4]"});
  EXPECT_DOUBLE_EQ(s.segments[1].x1, 9);
  EXPECT_DOUBLE_EQ(s.segments[1].x0, 2);
  EXPECT_EQ(s.segments[0].box, (std::vector<double>{3, 4}));
  const auto parse = [&](const std::string& o) {
    config::FromYaml<Scene>(config::ParseYaml(text, "s.yaml"), "s.yaml", {o});
  };
  testing::ExpectErrorContains([&] { parse("segments[2].x0=1"); }, {"has 2 elements", "index 2"});
  testing::ExpectErrorContains([&] { parse("segments[a].x0=1"); }, {"key[index]"});
  testing::ExpectErrorContains([&] { parse("name[0].x0=1"); }, {"'name' is not a list"});
  testing::ExpectErrorContains([&] { parse("segments[0].y9=1"); },
                               {"unknown key 'segments[0].y9'"});
}

TEST(Config, VectorOfStructsRoundTripsAndIsDocumented) {
  const Scene s = ParseScene("name: t\nsegments:\n  - {x0: 0.25, x1: 7, box: [1]}\n  - {x0: -3}\n");
  const std::string text = config::ToYaml(s);
  const Scene back = config::FromYaml<Scene>(config::ParseYaml(text, "round"), "round");
  EXPECT_EQ(config::ToYaml(back), text);
  ASSERT_EQ(back.segments.size(), 2u);
  EXPECT_DOUBLE_EQ(back.segments[0].x0, 0.25);
  EXPECT_EQ(back.segments[0].box, (std::vector<double>{1}));
  EXPECT_DOUBLE_EQ(back.segments[1].x0, -3);
  Scene empty;
  empty.segments.clear();
  const std::string empty_text = config::ToYaml(empty);
  EXPECT_TRUE(config::FromYaml<Scene>(config::ParseYaml(empty_text, "e"), "e").segments.empty())
      << empty_text;

  const std::string table = config::ReferenceTable<Scene>();
  for (const char* key :
       {"`segments`", "`segments[].x0`", "`segments[].x1`", "`segments[].box`", "`inner.rate`"})
    EXPECT_NE(table.find(key), std::string::npos) << key << "\n" << table;
  EXPECT_NE(table.find("list of mapping"), std::string::npos);
  EXPECT_NE(table.find("`2 entries`"), std::string::npos) << table;
}

// Found by fuzz_config_yaml (tests/fuzz/corpus/config_yaml/regress_model_line_break and
// regress_list_key): a quoted value with a line break made multi-line errors (the experiment's
// Validate quotes it), and a key that is a list escaped as a yaml-cpp exception.
TEST(Config, LineBreaksInValuesAndNonScalarKeysAreErrors) {
  testing::ExpectErrorContains([] { config::ParseYaml("model: \"a\\nb\"\n", "nl.yaml"); },
                               {"nl.yaml:1", "'a\\nb'", "line break"});
  testing::ExpectErrorContains([] { config::ParseYaml("x:\n  - \"\\x01\"\n", "c.yaml"); },
                               {"c.yaml:2", "'\\x01'", "control character"});
  testing::ExpectErrorContains([] { config::ParseYaml("{[1]: 2}\n", "k.yaml"); },
                               {"k.yaml:1", "a key is a list"});
  testing::ExpectErrorContains([] { config::ParseYaml("? {a: 1}\n: 2\n", "m.yaml"); },
                               {"m.yaml:1", "a key is a mapping"});
  EXPECT_NO_THROW(config::ParseYaml("name: \"tab\\tinside\"\n", "tab.yaml"));
}

// Issue 18: a hidden-layer list is bounded before any network is built (a 10 M-entry list took
// 23.8 GB in the model constructor); errors name the source and the key.
TEST(LayerWidths, BoundsCountWidthAndWeights) {
  EXPECT_NO_THROW(CheckLayerWidths({560, 180, 180}, "c.yaml", "network.hidden"));
  EXPECT_NO_THROW(CheckLayerWidths(std::vector<int>(16, 1000), "c.yaml", "network.hidden"));
  testing::ExpectErrorContains([] { CheckLayerWidths({}, "c.yaml", "network.hidden"); },
                               {"c.yaml", "network.hidden", "empty"});
  testing::ExpectErrorContains(
      [] { CheckLayerWidths(std::vector<int>(17, 8), "c.yaml", "otnet.hidden"); },
      {"c.yaml", "otnet.hidden", "17 layers"});
  testing::ExpectErrorContains(
      [] {
        CheckLayerWidths({8, 0}, "c.yaml", "naive.hidden");
      },
      {"c.yaml", "naive.hidden[1]", "outside [1, 65536]"});
  // 8000 x 8000 = 6.4e7 weights > 5e7; 7000 x 7000 = 4.9e7 passes.
  testing::ExpectErrorContains(
      [] {
        CheckLayerWidths({8000, 8000}, "c.yaml", "network.hidden");
      },
      {"c.yaml", "network.hidden", "hidden-to-hidden weights"});
  EXPECT_NO_THROW(CheckLayerWidths({7000, 7000}, "c.yaml", "network.hidden"));
}

}  // namespace
}  // namespace foresight
