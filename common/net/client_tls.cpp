#include "common/net/client_tls.hpp"

#include <cstdlib>
#include <stdexcept>

#include <openssl/x509v3.h>

#include "common/net/http_client.hpp"

namespace tessera {

namespace net = boost::asio;
using error_code = boost::system::error_code;

std::shared_ptr<net::ssl::context> client_tls_context(const std::string& ca_file) {
  auto context = std::make_shared<net::ssl::context>(net::ssl::context::tls_client);
  context->set_options(net::ssl::context::default_workarounds | net::ssl::context::no_sslv2 |
                       net::ssl::context::no_sslv3 | net::ssl::context::no_tlsv1 |
                       net::ssl::context::no_tlsv1_1);
  context->set_verify_mode(net::ssl::verify_peer);
  error_code ec;
  if (ca_file.empty())
    context->set_default_verify_paths(ec);
  else
    context->load_verify_file(ca_file, ec);
  if (ec)
    throw std::runtime_error(
        ca_file.empty() ? "cannot load the system's CA certificates: " + ec.message()
                        : "cannot read CA certificates from " + ca_file + ": " + ec.message());
  return context;
}

std::string handshake_failure(SSL* ssl, const error_code& ec, const std::string& where) {
  const long verified = SSL_get_verify_result(ssl);
  if (verified != X509_V_OK)
    return "the certificate of " + where +
           " is not trusted: " + X509_verify_cert_error_string(verified) +
           (verified == X509_V_ERR_HOSTNAME_MISMATCH || verified == X509_V_ERR_IP_ADDRESS_MISMATCH
                ? ""
                : " (give the CA that signed it with --ca-file or $TESSERA_CA_FILE)");
  std::string reason = ec.message();
  // OpenSSL's words for a server that answered in plain HTTP.
  const bool plain = reason.find("wrong version number") != std::string::npos ||
                     reason.find("http request") != std::string::npos ||
                     reason.find("packet length too long") != std::string::npos;
  return "TLS handshake with " + where + " failed: " + reason +
         (plain ? " (the server speaks plain http:// there, not https://)" : "");
}

std::string ca_file_or_env(const std::string& option) {
  if (!option.empty()) return option;
  if (const char* env = std::getenv("TESSERA_CA_FILE"); env && *env) return env;
  return "";
}

}  // namespace tessera
