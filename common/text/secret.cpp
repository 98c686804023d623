#include "common/text/secret.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace tessera {

std::string resolve_secret(const std::string& value, const std::string& file, const char* env,
                           const std::string& what) {
  std::string secret = value;
  if (secret.empty() && !file.empty()) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read the " + what + " file " + file);
    std::ostringstream text;
    text << in.rdbuf();
    secret = text.str();
    while (!secret.empty() && (secret.back() == '\n' || secret.back() == '\r' ||
                               secret.back() == ' ' || secret.back() == '\t'))
      secret.pop_back();
    if (secret.empty()) throw std::runtime_error("the " + what + " file " + file + " is empty");
  }
  if (secret.empty() && env != nullptr)
    if (const char* from_env = std::getenv(env)) secret = from_env;
  // It travels in an HTTP header: no room for anything that would end or split it.
  for (const char c : secret)
    if (static_cast<unsigned char>(c) <= ' ' || c == 0x7f)
      throw std::runtime_error("the " + what +
                               " must not contain white space or control characters");
  return secret;
}

std::string loose_secret_file(const std::string& file, const std::string& what) {
  struct stat status {};
  if (file.empty() || ::stat(file.c_str(), &status) != 0) return "";
  if ((status.st_mode & (S_IRWXG | S_IRWXO)) == 0) return "";
  char mode[8];
  std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(status.st_mode & 07777));
  return "the " + what + " file " + file + " may be read by others than its owner (mode " + mode +
         "): chmod 600 " + file;
}

}  // namespace tessera
