// surfeledit-secure-probe: a C++ DDS participant (Debian's libddsc, which has the DDS Security
// plugins that the Python client's pip wheel lacks) for the security test and bench
// (tests/python/service/test_security.py, bench/service/bench_security_rtt.py).
//
//   surfeledit-secure-probe client   --domain D [--security CONF] --client-id ID --session NAME
//                                    [--surfels N] [--steps K] [--timeout-s T]
//       Opens NAME, uploads a slab + sphere of about N surfels, sets the regions, configures
//       algorithm "none" and makes K deform steps, each timed from write to reply. Prints
//       `key=value` lines: open=<status> ... step_ms=<ms> (one per step) updates=<count>;
//       exit code 0 when every request got an OK reply, 2 when one got none in time, 3 on an error.
//   surfeledit-secure-probe intruder --domain D [--security CONF] --victim ID --session NAME
//                                    [--seconds S]
//       Tries for S seconds what an attacker would: writes OP_OPEN_SESSION of NAME as client ID
//       and as itself (a request that reached the server would bind ID to this writer and take
//       NAME), and reads the replies of both ids' partitions and every update. Prints
//       participant=, writer=, readers= (created or the error), written=, matched_servers=,
//       replies_read=, updates_read=; exit code 0 (the test judges the counts).
//   surfeledit-secure-probe bench    --domain D --security CONF --plain-domain D2 --client-id ID --session NAME
//                                    [--surfels N] [--steps K]
//       The client's work against a secured server (D) and a plain one (D2) from one process, the
//       steps alternating between them; prints on_ms= and off_ms= per step.
//
// The security configuration goes through surfeledit::service::security_properties, as the server's.
//
// Files: secure_probe.hpp (arguments, topics, QoS, secured participants), secure_probe_client.cpp
// (client, bench), secure_probe_intruder.cpp (intruder).
#include <cstdio>
#include <stdexcept>
#include <string>

#include "secure_probe.hpp"

namespace surfeledit::probe {
namespace {

Args parse(int argc, char** argv) {
  if (argc < 2) throw std::invalid_argument("usage: surfeledit-secure-probe client|intruder|bench [options]");
  Args a;
  a.mode = argv[1];
  if (a.mode != "client" && a.mode != "intruder" && a.mode != "bench") {
    throw std::invalid_argument("mode must be client, intruder or bench");
  }
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--domain") a.domain = std::stoi(v);
    else if (k == "--security") a.security = v;
    else if (k == "--client-id") a.client_id = v;
    else if (k == "--victim") a.victim = v;
    else if (k == "--session") a.session = v;
    else if (k == "--surfels") a.surfels = std::stoul(v);
    else if (k == "--steps") a.steps = std::stoi(v);
    else if (k == "--timeout-s") a.timeout_s = std::stod(v);
    else if (k == "--seconds") a.seconds = std::stod(v);
    else if (k == "--plain-domain") a.plain_domain = std::stoi(v);
    else throw std::invalid_argument("unknown option " + k);
  }
  if (a.domain < 0 || a.domain > 232) throw std::invalid_argument("--domain must be in 0..232");
  return a;
}

}  // namespace
}  // namespace surfeledit::probe

int main(int argc, char** argv) {
  using namespace surfeledit::probe;
  try {
    const Args a = parse(argc, argv);
    const int rc = a.mode == "client" ? run_client(a) : a.mode == "bench" ? run_bench(a) : run_intruder(a);
    std::fflush(stdout);
    return rc;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "surfeledit-secure-probe: %s\n", e.what());
    std::printf("error=%s\n", e.what());
    return 3;
  }
}
