// Who may call which route: the token check, on its own.
#include "server/api/access.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "common/text/secret.hpp"

namespace tessera {
namespace {

const AccessPolicy both(AccessTokens{"client-secret", "worker-secret", ""});

int status_of(const AccessPolicy& policy, const char* role, const char* authorization) {
  const auto refused = policy.check(role, authorization);
  return refused ? refused->status : 0;
}

TEST(AccessTest, EachRoleTakesOnlyItsOwnToken) {
  EXPECT_EQ(status_of(both, role_client, "Bearer client-secret"), 0);
  EXPECT_EQ(status_of(both, role_worker, "Bearer worker-secret"), 0);
  EXPECT_EQ(status_of(both, role_client, "bearer client-secret"), 0);  // the scheme in any case
  EXPECT_EQ(status_of(both, role_client, "Bearer worker-secret"), 403);
  EXPECT_EQ(status_of(both, role_worker, "Bearer client-secret"), 403);
  for (const char* wrong :
       {"", "Bearer", "Bearer ", "Basic Y2xpZW50LXNlY3JldA==", "client-secret",
        "Bearer client-secre", "Bearer client-secretX", "Bearer CLIENT-SECRET"}) {
    EXPECT_EQ(status_of(both, role_client, wrong), 401) << wrong;
    EXPECT_EQ(status_of(both, role_worker, wrong), 401) << wrong;
  }
  EXPECT_EQ(status_of(both, "", ""), 0);  // public routes need nothing
}

TEST(AccessTest, RefusalsSayWhatIsWrongInTheErrorShapeAndChallenge) {
  const auto missing = both.check(role_client, "");
  ASSERT_TRUE(missing);
  EXPECT_NE(missing->body.find("\"missing_token\""), std::string::npos) << missing->body;
  ASSERT_EQ(missing->headers.size(), 1u);
  EXPECT_EQ(missing->headers[0].first, "WWW-Authenticate");
  const auto invalid = both.check(role_worker, "Bearer nope");
  ASSERT_TRUE(invalid);
  EXPECT_NE(invalid->body.find("\"invalid_token\""), std::string::npos) << invalid->body;
  const auto other = both.check(role_worker, "Bearer client-secret");
  ASSERT_TRUE(other);
  EXPECT_NE(other->body.find("\"wrong_role\""), std::string::npos) << other->body;
  // The client role's token is named as people know it.
  EXPECT_NE(missing->body.find("needs the API token"), std::string::npos) << missing->body;
  EXPECT_NE(other->body.find("the API token cannot be used here"), std::string::npos)
      << other->body;
  EXPECT_EQ(missing->body.find("client token"), std::string::npos) << missing->body;
  // No answer echoes a token.
  for (const auto& refused : {missing, invalid, other})
    EXPECT_EQ(refused->body.find("secret"), std::string::npos) << refused->body;
}

TEST(AccessTest, ARoleWithoutATokenIsOpen) {
  const AccessPolicy workers_only(AccessTokens{"", "worker-secret", ""});
  EXPECT_FALSE(workers_only.protects(role_client));
  EXPECT_TRUE(workers_only.protects(role_worker));
  EXPECT_EQ(status_of(workers_only, role_client, ""), 0);
  EXPECT_EQ(status_of(workers_only, role_worker, ""), 401);
  const AccessPolicy open(AccessTokens{});
  EXPECT_EQ(status_of(open, role_worker, "Bearer anything"), 0);
}

TEST(AccessTest, BearerTokenParsing) {
  EXPECT_EQ(bearer_token("Bearer abc"), "abc");
  EXPECT_EQ(bearer_token("BEARER  abc  "), "abc");
  EXPECT_FALSE(bearer_token("Bearer   "));
  EXPECT_FALSE(bearer_token("Bearerabc"));
  EXPECT_FALSE(bearer_token("Token abc"));
}

TEST(SecretTest, FromTheValueThenTheFileThenTheEnvironment) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("tessera-secret-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  { std::ofstream(dir / "token") << "from-file\n"; }
  { std::ofstream(dir / "empty") << "\n"; }
  ::setenv("TESSERA_TEST_SECRET", "from-env", 1);
  EXPECT_EQ(resolve_secret("given", (dir / "token").string(), "TESSERA_TEST_SECRET", "t"), "given");
  EXPECT_EQ(resolve_secret("", (dir / "token").string(), "TESSERA_TEST_SECRET", "t"), "from-file");
  EXPECT_EQ(resolve_secret("", "", "TESSERA_TEST_SECRET", "t"), "from-env");
  ::unsetenv("TESSERA_TEST_SECRET");
  EXPECT_EQ(resolve_secret("", "", "TESSERA_TEST_SECRET", "t"), "");
  EXPECT_THROW(resolve_secret("", (dir / "missing").string(), nullptr, "t"), std::runtime_error);
  EXPECT_THROW(resolve_secret("", (dir / "empty").string(), nullptr, "t"), std::runtime_error);
  EXPECT_THROW(resolve_secret("two words", "", nullptr, "t"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace tessera
