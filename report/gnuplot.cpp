#include "report/gnuplot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

extern char** environ;

namespace sinscal {

std::string gnuplot_printable(const std::string& s) {
  std::string out;
  for (char c : s) out += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? '?' : c;
  return out;
}

std::string gnuplot_quoted(const std::string& s) {
  std::string q = "'";
  for (char c : gnuplot_printable(s)) q += c == '\'' ? std::string("''") : std::string(1, c);
  return q + "'";
}

std::string gnuplot_number(double v) {
  if (std::isnan(v)) return "?";
  char b[32];
  std::snprintf(b, sizeof b, "%.9g", v);
  return b;
}

std::string gnuplot_script_path(const std::string& png_path) {
  const auto dot = png_path.rfind('.');
  return (dot != std::string::npos && png_path.find('/', dot) == std::string::npos
              ? png_path.substr(0, dot)
              : png_path) +
         ".gp";
}

int wait_for_program(pid_t pid, const std::string& what, const std::string& log,
                     std::string& messages) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR)
      throw std::runtime_error("waiting for " + what + ": " + std::string(std::strerror(errno)));
  std::ifstream in(log);
  std::ostringstream text;
  text << in.rdbuf();
  messages = text.str();
  in.close();
  std::remove(log.c_str());
  return status;
}

void run_gnuplot(const std::string& program, const std::string& script_path,
                 const std::string& png_path) {
  const std::string temp_png = png_path + ".tmp-" + std::to_string(::getpid());
  const std::string set_output = "output = " + gnuplot_quoted(temp_png);
  const std::string log = script_path + ".log";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> argv = {const_cast<char*>(program.c_str()), const_cast<char*>("-e"),
                             const_cast<char*>(set_output.c_str()),
                             const_cast<char*>(script_path.c_str()), nullptr};
  pid_t pid = 0;
  const int err = posix_spawnp(&pid, program.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (err != 0) {
    std::remove(log.c_str());
    throw std::runtime_error("cannot run " + program + ": " + std::strerror(err) +
                             " (install the Debian package gnuplot-nox; the script is " +
                             script_path + ")");
  }
  std::string messages;
  const int status = wait_for_program(pid, "gnuplot", log, messages);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::remove(temp_png.c_str());
    throw std::runtime_error(program + " failed on " + script_path + ": " + messages);
  }
  if (std::rename(temp_png.c_str(), png_path.c_str()) != 0)
    throw std::runtime_error(png_path + ": cannot replace: " + std::strerror(errno));
}

}  // namespace sinscal
