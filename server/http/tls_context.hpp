// The coordinator's TLS: a context made from a PEM certificate chain and its key.
#pragma once

#include <memory>
#include <string>

namespace boost::asio::ssl {
class context;
}

namespace tessera {

// TLS 1.2 or later. Throws std::runtime_error naming the file and OpenSSL's reason when
// either cannot be read or the key is not the certificate's.
std::shared_ptr<boost::asio::ssl::context> make_server_tls_context(const std::string& cert_file,
                                                                   const std::string& key_file);

}  // namespace tessera
