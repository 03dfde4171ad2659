// print_pdf: the certificate printed to PDF by headless Chromium (Debian's package chromium), as
// a browser prints it with the page's A4 print style.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "report/certificate.hpp"
#include "report/gnuplot.hpp"

extern char** environ;

namespace sinscal {

void print_pdf(const std::string& html_path, const std::string& pdf_path,
               const std::string& chromium) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const std::string url = "file://" + fs::absolute(html_path, ec).string();
  const std::string temp_pdf = pdf_path + ".tmp-" + std::to_string(getpid());
  const fs::path profile =
      fs::temp_directory_path() / ("sinscal-chromium-" + std::to_string(getpid()));
  const std::string log = temp_pdf + ".log";
  std::vector<std::string> args = {chromium,
                                   "--headless",
                                   "--no-sandbox",
                                   "--disable-gpu",
                                   "--no-first-run",
                                   "--no-pdf-header-footer",
                                   "--user-data-dir=" + profile.string(),
                                   "--print-to-pdf=" + temp_pdf,
                                   url};
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int err = posix_spawnp(&pid, chromium.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (err != 0) {
    std::remove(log.c_str());
    if (err == ENOENT)
      throw ChromiumMissing(chromium +
                            " is not installed (the Debian package chromium prints "
                            "the PDF)");
    throw std::runtime_error("cannot run " + chromium + ": " + std::strerror(err));
  }
  std::string messages;
  const int status = wait_for_program(pid, "chromium", log, messages);
  fs::remove_all(profile, ec);
  std::string head;
  {
    std::ifstream in(temp_pdf, std::ios::binary);
    head.resize(5);
    if (!in.read(head.data(), 5)) head.clear();
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || head != "%PDF-") {
    std::remove(temp_pdf.c_str());
    if (messages.size() > 2000) messages = messages.substr(messages.size() - 2000);
    throw std::runtime_error(chromium + " did not print " + html_path + " to PDF: " + messages);
  }
  if (std::rename(temp_pdf.c_str(), pdf_path.c_str()) != 0) {
    std::remove(temp_pdf.c_str());
    throw std::runtime_error(pdf_path + ": cannot write: " + std::strerror(errno));
  }
}

}  // namespace sinscal
