// TLS end to end, as a user would set it up: a CA and a server certificate made with the
// openssl command, a coordinator serving HTTPS with them, an external worker and the CLI
// trusting the CA through --ca-file (or $TESSERA_CA_FILE).
#include <sys/wait.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/image/image_io.hpp"
#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::CliRun;
using test::contains;
using test::Farm;

// Runs the openssl command; false when it fails.
bool openssl(const std::string& arguments, const fs::path& log) {
  const std::string command = "openssl " + arguments + " >>" + log.string() + " 2>&1";
  return std::system(command.c_str()) == 0;
}

struct Certificates {
  fs::path ca;          // the CA that signs `cert`
  fs::path cert, key;   // for localhost and 127.0.0.1
  fs::path other_ca;    // a CA nobody here trusts...
  fs::path other_cert;  // ...and a certificate of it, for the same names
  fs::path other_key;
  fs::path wrong_cert;  // signed by `ca`, but for another name only
  fs::path wrong_key;
};

// A CA named `name` in `dir`, and `signs` certificates for `names` (subjectAltName syntax).
bool make_ca(const fs::path& dir, const std::string& name, const fs::path& log) {
  return openssl(
      "req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 "
      "-subj '/CN=Tessera test " +
          name + "' -keyout " + (dir / (name + ".key")).string() + " -out " +
          (dir / (name + ".pem")).string(),
      log);
}

bool make_cert(const fs::path& dir, const std::string& ca, const std::string& name,
               const std::string& names, const fs::path& log) {
  const fs::path ext = dir / (name + ".ext");
  test::write_text(ext, "subjectAltName=" + names + "\n");
  const std::string key = (dir / (name + ".key")).string();
  const std::string csr = (dir / (name + ".csr")).string();
  return openssl("req -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -subj '/CN=" + name +
                     "' -keyout " + key + " -out " + csr,
                 log) &&
         openssl("x509 -req -days 2 -in " + csr + " -CA " + (dir / (ca + ".pem")).string() +
                     " -CAkey " + (dir / (ca + ".key")).string() + " -CAcreateserial -out " +
                     (dir / (name + ".pem")).string() + " -extfile " + ext.string(),
                 log);
}

std::optional<Certificates> make_certificates(const fs::path& dir) {
  const fs::path log = dir / "openssl.log";
  const std::string here = "DNS:localhost,IP:127.0.0.1";
  if (!make_ca(dir, "ca", log) || !make_ca(dir, "other-ca", log) ||
      !make_cert(dir, "ca", "server", here, log) ||
      !make_cert(dir, "other-ca", "other-server", here, log) ||
      !make_cert(dir, "ca", "wrong-server", "DNS:farm.example", log))
    return std::nullopt;
  return Certificates{dir / "ca.pem",           dir / "server.pem",       dir / "server.key",
                      dir / "other-ca.pem",     dir / "other-server.pem", dir / "other-server.key",
                      dir / "wrong-server.pem", dir / "wrong-server.key"};
}

std::vector<std::string> tls_args(const fs::path& cert, const fs::path& key) {
  return {"--tls-cert", cert.string(), "--tls-key", key.string()};
}

TEST(FarmTlsTest, AJobRendersOverHttpsBitForBitAndEveryMistakeIsOneLineAndExitThree) {
  if (std::system("openssl version >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "the openssl command is not installed; deploy/install-deps.sh installs it";
  const fs::path pki = test::fresh_dir("tls-pki");
  const auto certs = make_certificates(pki);
  ASSERT_TRUE(certs) << "openssl failed; see " << (pki / "openssl.log");

  // The working copies the coordinator reads, replaced below to show SIGHUP.
  const fs::path cert = pki / "in-use.pem";
  const fs::path key = pki / "in-use.key";
  fs::copy_file(certs->cert, cert);
  fs::copy_file(certs->key, key);
  Farm farm("tls", 0, tls_args(cert, key));
  const std::string port = std::to_string(farm.port());
  const std::string https = "https://127.0.0.1:" + port;
  const std::string ca = certs->ca.string();
  const auto cli = [&](std::vector<std::string> args, const std::vector<std::string>& env = {}) {
    std::vector<std::string> prefix;
    if (!env.empty()) {
      prefix = {"/usr/bin/env"};
      prefix.insert(prefix.end(), env.begin(), env.end());
    }
    return test::run_cli(farm.dir(), args, 60s, prefix);
  };

  // An external worker, by name (the certificate's DNS name), trusting the CA.
  test::Process worker(TESSERA_WORKER_BIN,
                       {"--server", "https://localhost:" + port, "--ca-file", ca, "--threads", "2",
                        "--name", "tls-worker", "--log-level", "info"},
                       farm.dir() / "worker.log");

  // A job submitted and fetched over HTTPS is bit for bit the local render.
  const nlohmann::json scene = test::showcase(64, 48, 2, 16);
  const fs::path scene_file = farm.dir() / "scene.json";
  test::write_text(scene_file, scene.dump());
  const fs::path farm_exr = farm.dir() / "farm.exr";
  const CliRun submitted = cli({"submit", scene_file.string(), "--server", https, "--ca-file", ca,
                                "--wait", "-o", farm_exr.string()});
  ASSERT_EQ(submitted.exit_code, 0)
      << submitted.output << test::read_text(farm.dir() / "worker.log");
  const fs::path local_exr = farm.dir() / "local.exr";
  const CliRun rendered = cli({"render", scene_file.string(), "-o", local_exr.string()});
  ASSERT_EQ(rendered.exit_code, 0) << rendered.output;
  EXPECT_TRUE(test::same_pixels(read_image(farm_exr), read_image(local_exr)));
  // $TESSERA_CA_FILE does what --ca-file does.
  const CliRun listed = cli({"list", "--server", https}, {"TESSERA_CA_FILE=" + ca});
  EXPECT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_TRUE(contains(listed.output, "completed")) << listed.output;
  // What a container's health check runs, over TLS.
  const CliRun health = cli({"health", "--server", https, "--ca-file", ca});
  EXPECT_EQ(health.exit_code, 0) << health.output;
  EXPECT_EQ(health.output, "ok\n");

  // A certificate the CLI does not trust: the system's CAs do not know ours, nor does another.
  for (const auto& extra :
       std::vector<std::vector<std::string>>{{}, {"--ca-file", certs->other_ca.string()}}) {
    std::vector<std::string> args{"list", "--server", https};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliRun untrusted = cli(args);
    EXPECT_EQ(untrusted.exit_code, 3) << untrusted.output;
    EXPECT_TRUE(contains(untrusted.output, "is not trusted")) << untrusted.output;
    EXPECT_EQ(std::count(untrusted.output.begin(), untrusted.output.end(), '\n'), 1)
        << untrusted.output;
  }
  // A worker that does not trust it stops at once, saying so, with the same code.
  {
    test::Process doubter(TESSERA_WORKER_BIN, {"--server", https, "--threads", "1"},
                          farm.dir() / "doubter.log");
    const auto status = doubter.wait_for(20s);
    ASSERT_TRUE(status) << "a worker retried an untrusted certificate forever";
    EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 3) << *status;
    EXPECT_TRUE(contains(test::read_text(farm.dir() / "doubter.log"), "is not trusted"))
        << test::read_text(farm.dir() / "doubter.log");
  }
  // Plain HTTP to the TLS port gets a plain answer saying so.
  const CliRun plain_to_tls = cli({"list", "--server", "http://127.0.0.1:" + port});
  EXPECT_EQ(plain_to_tls.exit_code, 3) << plain_to_tls.output;
  EXPECT_TRUE(contains(plain_to_tls.output, "this port speaks TLS")) << plain_to_tls.output;

  // A certificate for another name, from the trusted CA: refused for the name.
  {
    Farm wrong("tls-wrong-name", 0, tls_args(certs->wrong_cert, certs->wrong_key));
    const CliRun mismatched = cli(
        {"list", "--server", "https://127.0.0.1:" + std::to_string(wrong.port()), "--ca-file", ca});
    EXPECT_EQ(mismatched.exit_code, 3) << mismatched.output;
    EXPECT_TRUE(contains(mismatched.output, "mismatch")) << mismatched.output;
  }
  // https:// to a plain port.
  {
    Farm plain("tls-plain", 0);
    const CliRun tls_to_plain = cli(
        {"list", "--server", "https://127.0.0.1:" + std::to_string(plain.port()), "--ca-file", ca});
    EXPECT_EQ(tls_to_plain.exit_code, 3) << tls_to_plain.output;
    EXPECT_TRUE(contains(tls_to_plain.output, "plain http://")) << tls_to_plain.output;
    EXPECT_EQ(plain.api().jobs("", 10)["jobs"].size(), 0u) << "the plain server still serves";
  }

  // SIGHUP reads the files again: after they are replaced by a certificate of the other CA,
  // new connections trust that CA and not the first.
  fs::copy_file(certs->other_cert, cert, fs::copy_options::overwrite_existing);
  fs::copy_file(certs->other_key, key, fs::copy_options::overwrite_existing);
  farm.server().signal(SIGHUP);
  EXPECT_TRUE(test::eventually(
      [&] {
        return cli({"list", "--server", https, "--ca-file", certs->other_ca.string()}).exit_code ==
               0;
      },
      20s))
      << test::read_text(farm.dir() / "server.log");
  EXPECT_EQ(cli({"list", "--server", https, "--ca-file", ca}).exit_code, 3);
  // A reload that fails keeps the certificate in use, and says why.
  test::write_text(cert, "not a certificate");
  farm.server().signal(SIGHUP);
  EXPECT_TRUE(test::eventually(
      [&] { return contains(test::read_text(farm.dir() / "server.log"), "stays"); }, 20s))
      << test::read_text(farm.dir() / "server.log");
  EXPECT_EQ(cli({"list", "--server", https, "--ca-file", certs->other_ca.string()}).exit_code, 0);
  worker.signal(SIGTERM);
  EXPECT_TRUE(worker.wait_for(20s).has_value());
}

}  // namespace
}  // namespace tessera
