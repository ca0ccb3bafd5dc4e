// Test certificates made at run time with the openssl command-line tool
// (Debian's openssl package), so no key material lives in the tree and none
// can expire: a CA, a server certificate it signed for localhost and
// 127.0.0.1, one it signed for another name only, a client certificate it
// signed, and an unrelated CA with its own client certificate.
#ifndef PATHD_TESTS_SERVER_TEST_CERTS_H_
#define PATHD_TESTS_SERVER_TEST_CERTS_H_

#include <cstdlib>
#include <filesystem>
#include <string>

#include "absl/strings/str_cat.h"

namespace pathd::testing {

struct TestCerts {
  std::filesystem::path dir;
  std::string ca;           // trusted CA certificate
  std::string server_cert;  // CN/SAN localhost, IP 127.0.0.1, signed by ca
  std::string server_key;
  std::string other_name_cert;  // SAN DNS:pathd.test only, signed by ca
  std::string other_name_key;
  std::string client_cert;  // signed by ca
  std::string client_key;
  std::string other_ca;           // an unrelated CA
  std::string other_client_cert;  // signed by other_ca
  std::string other_client_key;
};

namespace internal {

// Runs a shell command quietly; true when it exited 0.
inline bool Run(const std::string& command) {
  return std::system(absl::StrCat(command, " >/dev/null 2>&1").c_str()) == 0;
}

// P-256 keys: generated in milliseconds, unlike RSA.
inline constexpr char kNewKey[] =
    "-newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes";

inline bool MakeCa(const std::filesystem::path& dir, const std::string& name) {
  return Run(absl::StrCat("openssl req -x509 ", kNewKey, " -days 2 -subj /CN=",
                          name, " -keyout ", (dir / (name + ".key")).string(),
                          " -out ", (dir / (name + ".crt")).string(),
                          " -addext basicConstraints=critical,CA:TRUE",
                          " -addext keyUsage=critical,keyCertSign,cRLSign"));
}

// A leaf certificate `name`.crt/.key with `san` signed by CA `ca`.
inline bool MakeLeaf(const std::filesystem::path& dir, const std::string& ca,
                     const std::string& name, const std::string& cn,
                     const std::string& san) {
  const std::string base = (dir / name).string();
  const std::string ca_base = (dir / ca).string();
  return Run(absl::StrCat(
             "openssl req -new ", kNewKey, " -subj /CN=", cn, " -keyout ", base,
             ".key -out ", base, ".csr",
             san.empty() ? ""
                         : absl::StrCat(" -addext subjectAltName=", san))) &&
         Run(absl::StrCat("openssl x509 -req -in ", base, ".csr -CA ", ca_base,
                          ".crt -CAkey ", ca_base,
                          ".key -CAcreateserial -days 2",
                          " -copy_extensions copy -out ", base, ".crt"));
}

}  // namespace internal

// Writes every certificate into `dir` (which must exist); false when the
// openssl tool is missing or failed.
inline bool MakeTestCerts(const std::filesystem::path& dir, TestCerts* certs) {
  using internal::MakeCa;
  using internal::MakeLeaf;
  if (!MakeCa(dir, "ca") || !MakeCa(dir, "other_ca") ||
      !MakeLeaf(dir, "ca", "server", "localhost",
                "DNS:localhost,IP:127.0.0.1") ||
      !MakeLeaf(dir, "ca", "other_name", "pathd.test", "DNS:pathd.test") ||
      !MakeLeaf(dir, "ca", "client", "robot-7", "") ||
      !MakeLeaf(dir, "other_ca", "other_client", "intruder", "")) {
    return false;
  }
  auto file = [&dir](const std::string& name) { return (dir / name).string(); };
  certs->dir = dir;
  certs->ca = file("ca.crt");
  certs->server_cert = file("server.crt");
  certs->server_key = file("server.key");
  certs->other_name_cert = file("other_name.crt");
  certs->other_name_key = file("other_name.key");
  certs->client_cert = file("client.crt");
  certs->client_key = file("client.key");
  certs->other_ca = file("other_ca.crt");
  certs->other_client_cert = file("other_client.crt");
  certs->other_client_key = file("other_client.key");
  return true;
}

}  // namespace pathd::testing

#endif  // PATHD_TESTS_SERVER_TEST_CERTS_H_
