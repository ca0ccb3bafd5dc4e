// pathd's gRPC listening credentials: plaintext, TLS (--tls_cert/--tls_key)
// or mutual TLS (--tls_client_ca). The PEM files are checked with OpenSSL at
// start-up so a bad file is reported by name instead of as a failed listen.
#ifndef PATHD_SERVER_TLS_H_
#define PATHD_SERVER_TLS_H_

#include <grpcpp/security/server_credentials.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"

namespace pathd::server {

struct TlsFiles {
  // PEM certificate chain (server certificate first) and its private key;
  // both empty = plaintext.
  std::string cert;
  std::string key;
  // PEM CA certificates client certificates must chain to; non-empty =
  // mutual TLS (a client without a valid certificate cannot connect).
  std::string client_ca;
};

// Insecure credentials when no file is given, else SSL credentials.
// INVALID_ARGUMENT when only one of cert/key is given, client_ca is given
// without them, a file holds no PEM certificate / key, or the key does not
// belong to the certificate; NOT_FOUND / INTERNAL when a file cannot be read.
// Every message names the flag and the file.
absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> MakeServerCredentials(
    const TlsFiles& files);

}  // namespace pathd::server

#endif  // PATHD_SERVER_TLS_H_
