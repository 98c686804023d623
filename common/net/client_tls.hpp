// The client side of TLS for HttpClient (common/net/http_client.cpp): the context its
// connections share, and a failed handshake said in words a user can act on.
#pragma once

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <memory>
#include <string>

#include <openssl/ssl.h>
#include <boost/asio/ssl.hpp>

namespace tessera {

// Peers are verified against `ca_file`, or the system's store; TLS 1.2 at least.
std::shared_ptr<boost::asio::ssl::context> client_tls_context(const std::string& ca_file);

// Why a handshake with `where` failed.
std::string handshake_failure(SSL* ssl, const boost::system::error_code& ec,
                              const std::string& where);

}  // namespace tessera
