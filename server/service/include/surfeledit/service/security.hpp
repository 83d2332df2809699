// DDS Security switch (proto/PROTOCOL.md, "Security"): a small `key = value` file names one
// participant's identity, the two CAs and the signed governance and permissions documents
// (scripts/make_security.py writes one per user); security_properties() turns it into the
// participant QoS properties of Cyclone's built-in authentication, access control and
// cryptography plugins. The one place where that configuration is made: the server's
// participant and the test and bench participants (tests/service/secure_probe.cpp) use it.
#pragma once

#include <string>
#include <vector>

namespace surfeledit::service {

// One participant QoS property ("dds.sec.*").
struct SecurityProperty {
  std::string name;   // e.g. "dds.sec.auth.identity_ca"
  std::string value;  // e.g. "file:/abs/path/ca.pem"
};

// The keys of a security configuration file, each naming a file (relative paths are relative to
// the configuration file):
//   identity_ca, identity_certificate, private_key   authentication (X.509 PEM, key unencrypted)
//   permissions_ca, governance, permissions          access control (governance and permissions
//                                                    S/MIME signed by the permissions CA)
// and, optional, `user` (the certificate's CN; clients prefix their ids with it, ignored here) and
// `plugin_dir`: the directory of libdds_security_{auth,ac,crypto}.so (default: where
// Debian's libddsc0debian installs them, found at build time). '#' starts a comment line.
//
// Reads `config_path` and returns the properties (every file checked to be a readable regular
// file). Throws std::invalid_argument naming the file, the line or key and the value on any error:
// a missing or unknown key, a repeated key, a missing file.
std::vector<SecurityProperty> security_properties(const std::string& config_path);

}  // namespace surfeledit::service
