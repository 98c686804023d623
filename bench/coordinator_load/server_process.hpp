// The coordinator under test: a tessera-server this program starts (or one it is pointed
// at), and what /proc says about it.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace tessera::load {

// CPU time (user + system) of a process so far, in seconds; from /proc/PID/stat.
double process_cpu_seconds(pid_t pid);
// A "Vm...:" line of /proc/PID/status in KiB (VmRSS, VmHWM); 0 when it cannot be read.
std::int64_t process_status_kib(pid_t pid, const std::string& field);

// Bytes a process has moved so far, from /proc/PID/io: through read/write calls of any
// kind (sockets included), and to or from the block device.
struct ProcessIo {
  std::int64_t rchar = 0;
  std::int64_t wchar = 0;
  std::int64_t read_bytes = 0;
  std::int64_t write_bytes = 0;
};
ProcessIo process_io(pid_t pid);

// The whole machine's CPU time so far, in seconds summed over its CPUs (/proc/stat): what
// ran (user, nice, system, interrupts), what the hypervisor took (steal) and idle time
// waiting for the disk (iowait). Shows whether anything else competed during a run.
struct MachineCpu {
  double busy = 0;
  double steal = 0;
  double iowait = 0;
};
MachineCpu machine_cpu();

class ServerProcess {
 public:
  // Starts `binary` listening on a free loopback port with its data in `data_dir`, no
  // local workers, and `extra_args`; returns once it has written its port file.
  ServerProcess(const std::string& binary, const std::filesystem::path& data_dir,
                const std::vector<std::string>& extra_args);
  // SIGTERM, then waits for it to exit (it writes images still pending first).
  ~ServerProcess();
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  pid_t pid() const { return pid_; }
  std::uint16_t port() const { return port_; }

 private:
  pid_t pid_ = -1;
  std::uint16_t port_ = 0;
};

}  // namespace tessera::load
