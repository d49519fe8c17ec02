#include "core/h5.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "tests/test_util.h"

namespace foresight {
namespace {

// Issue 18, defect 2: a write that fails (full disk) is an Error naming the file, and nothing
// half-written is left where the file is expected (nor its temporary).
TEST(H5, WriteAtomicallyLeavesNothingWhenTheDiskIsFull) {
  testing::TempDir dir;
  const std::string path = dir.File("big.h5");
  const Eigen::MatrixXd big = Eigen::MatrixXd::Ones(200, 200);  // 320 kB
  {
    const testing::ScopedFileSizeLimit limit(64 * 1024);
    testing::ExpectErrorContains(
        [&] { h5::WriteAtomically(path, [&](h5::File* f) { f->WriteMatrix("/m", big); }); },
        {"big.h5"});
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  // A writer that fails for its own reasons leaves nothing either; a complete write lands.
  EXPECT_THROW(h5::WriteAtomically(path, [](h5::File*) { throw Error("stop"); }), Error);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  h5::WriteAtomically(path, [&](h5::File* f) { f->WriteMatrix("/m", big); });
  EXPECT_TRUE(h5::File::Open(path).ReadMatrixD("/m", 200, 200).isApprox(big));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

TEST(H5, RoundTripsArraysAttributesAndStrings) {
  testing::TempDir dir;
  const std::string path = dir.File("a.h5");
  Eigen::MatrixXd m(2, 3);
  m << 1, 2, 3, 4, 5, 6;
  Eigen::MatrixXf mf = m.cast<float>() * 0.5f;
  std::vector<std::int64_t> ints{3, -1, 7};
  {
    h5::File f = h5::File::Create(path);
    f.WriteMatrix("/g/h/m", m);
    f.WriteMatrix("/g/mf", mf);
    f.Write("/ints", ints.data(), {3});
    f.WriteString("/text", "hello: world\n");
    f.SetAttr("/", "name", std::string("x"));
    f.SetAttr("/g", "count", std::int64_t{42});
    f.SetAttr("/g/h/m", "scale", 2.5);
  }
  h5::File f = h5::File::Open(path);
  EXPECT_TRUE(f.ReadMatrixD("/g/h/m", 2, 3).isApprox(m));
  EXPECT_TRUE(f.ReadMatrixF("/g/mf").isApprox(mf));
  EXPECT_EQ(f.ReadInt("/ints").data, ints);
  EXPECT_EQ(f.ReadString("/text"), "hello: world\n");
  EXPECT_EQ(f.GetStringAttr("/", "name"), "x");
  EXPECT_EQ(f.GetIntAttr("/g", "count"), 42);
  EXPECT_DOUBLE_EQ(f.GetDoubleAttr("/g/h/m", "scale"), 2.5);
  EXPECT_EQ(f.List("/g"), (std::vector<std::string>{"h", "mf"}));
  EXPECT_TRUE(f.Exists("/g/h/m"));
  EXPECT_FALSE(f.Exists("/g/nope/m"));
}

// Issue 18: a resumed run's artifact is compared bit for bit with an uninterrupted one, so a file
// must not record when its objects were made (HDF5 stores modification times by default).
TEST(H5, SameContentWrittenAtDifferentTimesIsTheSameFile) {
  testing::TempDir dir;
  auto write = [&](const std::string& name) {
    h5::File f = h5::File::Create(dir.File(name));
    f.WriteMatrix("/g/h/m", Eigen::MatrixXd::Identity(3, 2));
    f.WriteString("/text", "config: 1");
    f.SetAttr("/g", "count", std::int64_t{42});
  };
  write("a.h5");
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));  // object times have 1 s resolution
  write("b.h5");
  EXPECT_EQ(testing::ReadText(dir.File("a.h5")), testing::ReadText(dir.File("b.h5")));
}

TEST(H5, ErrorsNameFileAndObject) {
  testing::TempDir dir;
  const std::string path = dir.File("b.h5");
  {
    h5::File f = h5::File::Create(path);
    Eigen::MatrixXd m = Eigen::MatrixXd::Ones(4, 4);
    f.WriteMatrix("/m", m);
  }
  h5::File f = h5::File::Open(path);
  testing::ExpectErrorContains([&] { f.ReadDouble("/missing"); },
                               {path, "missing dataset '/missing'"});
  testing::ExpectErrorContains([&] { f.ReadMatrixD("/m", 3, 4); },
                               {path, "'/m'", "4x4", "expected 3x4"});
  testing::ExpectErrorContains([&] { f.GetIntAttr("/", "nope"); },
                               {path, "missing attribute 'nope'"});
  testing::ExpectErrorContains([&] { f.ReadInt("/m"); }, {"wrong element type"});
  testing::ExpectErrorContains([] { h5::File::Open("/nonexistent/file.h5"); },
                               {"/nonexistent/file.h5", "not found"});
}

TEST(H5, ScalarReadsRefuseArrays) {
  testing::TempDir dir;
  const std::string path = dir.File("arrays.h5");
  {
    h5::File f = h5::File::Create(path);
    f.SetAttr("/g", "marker", std::int64_t{1});
  }
  {  // Arrays written by another tool, where this reader expects single values.
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t group = H5Gopen2(file, "/g", H5P_DEFAULT);
    const hsize_t three = 3;
    const hid_t space = H5Screate_simple(1, &three, nullptr);
    const std::int64_t ints[3] = {1, 2, 3};
    const double doubles[3] = {1, 2, 3};
    const hid_t str = H5Tcopy(H5T_C_S1);
    H5Tset_size(str, 4);
    const char strings[12] = {'a', 'b', 'c', 0, 'd', 'e', 'f', 0, 'g', 'h', 'i', 0};
    const hid_t a1 = H5Acreate2(group, "ints", H5T_NATIVE_INT64, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a1, H5T_NATIVE_INT64, ints);
    const hid_t a2 =
        H5Acreate2(group, "doubles", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a2, H5T_NATIVE_DOUBLE, doubles);
    const hid_t a3 = H5Acreate2(group, "strings", str, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a3, str, strings);
    const hid_t ds = H5Dcreate2(file, "/texts", str, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(ds, str, H5S_ALL, H5S_ALL, H5P_DEFAULT, strings);
    for (hid_t a : {a1, a2, a3}) H5Aclose(a);
    H5Dclose(ds);
    H5Tclose(str);
    H5Sclose(space);
    H5Gclose(group);
    H5Fclose(file);
  }
  h5::File f = h5::File::Open(path);
  EXPECT_EQ(f.GetIntAttr("/g", "marker"), 1);
  testing::ExpectErrorContains([&] { f.GetIntAttr("/g", "ints"); },
                               {path, "'ints'", "'/g'", "3 elements"});
  testing::ExpectErrorContains([&] { f.GetDoubleAttr("/g", "doubles"); },
                               {path, "'doubles'", "'/g'", "3 elements"});
  testing::ExpectErrorContains([&] { f.GetStringAttr("/g", "strings"); },
                               {path, "'strings'", "'/g'", "3 elements"});
  testing::ExpectErrorContains([&] { f.ReadString("/texts"); }, {path, "'/texts'", "3 elements"});
}

// Fuzz finding (tests/fuzz/corpus/directional_artifact/regress_newline_model_type): an edited
// model_type "e\n_min[" was echoed into a two-line loader error. String attributes must be text.
TEST(H5, StringAttributesWithControlCharactersAreRefused) {
  testing::TempDir dir;
  const std::string path = dir.File("control.h5");
  {
    h5::File f = h5::File::Create(path);
    f.SetAttr("/", "model_type", std::string("e\n_min["));
    f.SetAttr("/", "plain", std::string("span_predictor"));
    f.Close();
  }
  h5::File f = h5::File::Open(path);
  EXPECT_EQ(f.GetStringAttr("/", "plain"), "span_predictor");
  testing::ExpectErrorContains([&] { f.GetStringAttr("/", "model_type"); },
                               {path, "'model_type'", "control character 10 at position 1"});
}

TEST(H5, TruncatedAndForeignFilesAreClearErrors) {
  testing::TempDir dir;
  const std::string path = dir.File("c.h5");
  {
    h5::File f = h5::File::Create(path);
    Eigen::MatrixXd m = Eigen::MatrixXd::Random(200, 200);
    f.WriteMatrix("/m", m);
  }
  testing::Truncate(path, 3000);
  testing::ExpectErrorContains([&] { h5::File::Open(path).ReadDouble("/m"); }, {path});
  testing::WriteText(dir.File("text.h5"), "this is not hdf5\n");
  testing::ExpectErrorContains([&] { h5::File::Open(dir.File("text.h5")); },
                               {"text.h5", "not a readable HDF5 file"});
}

}  // namespace
}  // namespace foresight
