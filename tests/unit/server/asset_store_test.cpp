// The coordinator's asset store: what collection removes, and what it must keep.
#include <unistd.h>

#include <fstream>

#include <gtest/gtest.h>

#include "common/protocol/asset_digest.hpp"
#include "server/api/asset_collector.hpp"
#include "server/api/asset_store.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;

class AssetStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("tessera-assets-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // An asset file whose time of last reference was `age` ago.
  std::string add(char fill, std::chrono::seconds age) {
    const std::string digest(64, fill);
    std::ofstream(dir_ / digest) << "bytes";
    fs::last_write_time(dir_ / digest, fs::file_time_type::clock::now() - age);
    return digest;
  }

  fs::path dir_;
};

TEST_F(AssetStoreTest, CollectionRemovesOnlyOldAssetsNoJobNeeds) {
  AssetStore store(dir_, 1 << 20);
  const auto day = std::chrono::hours(24);
  const std::string old_unused = add('a', 8 * day);
  const std::string old_in_use = add('b', 8 * day);
  const std::string recent = add('c', 1 * day);
  std::ofstream(dir_ / "not-an-asset") << "x";
  EXPECT_EQ(store.collect(std::chrono::hours(7 * 24), {old_in_use}), 1u);
  EXPECT_FALSE(store.find(old_unused));
  EXPECT_TRUE(store.find(old_in_use));
  EXPECT_TRUE(store.find(recent));
  EXPECT_TRUE(fs::exists(dir_ / "not-an-asset"));
}

TEST_F(AssetStoreTest, AnAssetASubmissionReferencesIsNotOldAnyMore) {
  AssetStore store(dir_, 1 << 20);
  const std::string digest = add('d', std::chrono::hours(24 * 30));
  ASSERT_TRUE(store.reference(digest));
  EXPECT_EQ(store.collect(std::chrono::hours(24), {}), 0u);
  EXPECT_TRUE(store.find(digest));
  EXPECT_FALSE(store.reference(std::string(64, 'e')));
  EXPECT_FALSE(store.reference("../../etc/passwd"));
}

TEST(AssetCollectorTest, FindsEveryDigestAStoredSceneNames) {
  const std::string a(64, 'a'), b(64, '0');
  const std::string scene =
      R"({"objects": [{"asset": "sha256:)" + a + R"(", "files": {"x": "sha256:)" + b +
      R"("}}, {"name": "sha256:short"}, {"name": "sha256:)" + std::string(64, 'G') + R"("}]})";
  EXPECT_EQ(protocol::digests_named_in(scene), (std::set<std::string>{a, b}));
}

TEST(AssetDigestTest, ReadsOnlyItsFormAndWritesItBack) {
  using protocol::AssetDigest;
  const std::string hex = "0123456789abcdef" + std::string(48, 'f');
  const auto digest = AssetDigest::parse("sha256:" + hex);
  ASSERT_TRUE(digest);
  EXPECT_EQ(digest->hex(), hex);
  EXPECT_EQ(digest->text(), "sha256:" + hex);
  EXPECT_EQ(digest->short_text(), "sha256:0123456789ab");
  EXPECT_EQ(AssetDigest::of_hex(hex), *digest);
  for (const std::string& bad :
       {hex, "sha256:" + hex.substr(1), "SHA256:" + hex, "sha256:" + hex + "0",
        "sha256:0123456789ABCDEF" + std::string(48, 'f'), "sha256:" + std::string(64, 'g'),
        std::string("md5:") + hex})
    EXPECT_FALSE(AssetDigest::parse(bad)) << bad;
  EXPECT_THROW(AssetDigest::of_hex("abc"), std::invalid_argument);
}

}  // namespace
}  // namespace tessera
