// OffscreenDisplay: the X display for offscreen rendering, or a private Xvfb.

#include "render/OffscreenDisplay.h"

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <X11/Xlib.h>

namespace caps::render {
namespace {

constexpr const char* kInstallHint = "install the Debian package xvfb, or run under xvfb-run -a";
constexpr std::chrono::seconds kStartTimeout{20};
constexpr std::chrono::seconds kStopTimeout{5};

/// Why an X display cannot be used for rendering, or nullopt when it can.
std::optional<std::string> displayProblem(const char* name)
{
  // Xlib's default error handlers exit the process; opening and querying do
  // not raise protocol errors, and a failed open returns null.
  Display* display = XOpenDisplay(name);
  if (display == nullptr)
    return std::string("cannot open X display ") + (name ? name : "(unset)");
  int opcode = 0, event = 0, error = 0;
  const bool glx = XQueryExtension(display, "GLX", &opcode, &event, &error) != 0;
  XCloseDisplay(display);
  if (!glx)
    return std::string("X display ") + name + " has no GLX extension, which VTK needs";
  return std::nullopt;
}

/// The Xvfb executable: $CAPS_XVFB when set, else on PATH (or in /usr/bin); "" when there is none.
std::string findXvfb()
{
  if (const char* chosen = std::getenv("CAPS_XVFB"))
    return ::access(chosen, X_OK) == 0 ? std::string(chosen) : std::string();
  std::vector<std::string> directories;
  if (const char* path = std::getenv("PATH"))
  {
    std::istringstream in(path);
    for (std::string dir; std::getline(in, dir, ':');)
      if (!dir.empty())
        directories.push_back(dir);
  }
  directories.push_back("/usr/bin");
  for (const std::string& dir : directories)
  {
    const std::string candidate = dir + "/Xvfb";
    if (::access(candidate.c_str(), X_OK) == 0)
      return candidate;
  }
  return {};
}

/// A file descriptor closed on scope exit.
class Fd
{
public:
  explicit Fd(int fd = -1) : fd_(fd) {}
  ~Fd() { reset(); }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  void reset(int fd = -1)
  {
    if (fd_ >= 0)
      ::close(fd_);
    fd_ = fd;
  }

private:
  int fd_;
};

/// Moves fd to a number >= 10 (close-on-exec), so the child's dup2 onto 0..3 never clobbers it.
int highFd(int fd)
{
  const int moved = ::fcntl(fd, F_DUPFD_CLOEXEC, 10);
  ::close(fd);
  if (moved < 0)
    throw std::runtime_error(std::string("cannot start Xvfb: fcntl failed: ") + std::strerror(errno));
  return moved;
}

/// Reads what the child wrote to its (unlinked) log file, trimmed to the last 2000 characters.
std::string readLog(int fd)
{
  std::string text;
  char buffer[4096];
  off_t offset = 0;
  for (;;)
  {
    const ssize_t n = ::pread(fd, buffer, sizeof buffer, offset);
    if (n <= 0)
      break;
    text.append(buffer, std::size_t(n));
    offset += n;
  }
  if (text.size() > 2000)
    text = "..." + text.substr(text.size() - 2000);
  while (!text.empty() && (text.back() == '\n' || text.back() == ' '))
    text.pop_back();
  return text;
}

/// Waits for pid to exit (SIGTERM, then SIGKILL after kStopTimeout) and reaps it.
void stopProcess(pid_t pid)
{
  if (pid <= 0)
    return;
  ::kill(pid, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + kStopTimeout;
  for (;;)
  {
    int status = 0;
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid || (r < 0 && errno != EINTR))
      return; // reaped, or not our child any more (ECHILD)
    if (std::chrono::steady_clock::now() > deadline)
      break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR)
  {}
}

/// True when pid (our child) has exited; reaps it.
bool hasExited(pid_t pid)
{
  int status = 0;
  pid_t r;
  do
    r = ::waitpid(pid, &status, WNOHANG);
  while (r < 0 && errno == EINTR);
  return r == pid || r < 0;
}

/// The display number Xvfb writes on @a fd ("N\n" once it accepts
/// connections; EOF means it died), waited for up to kStartTimeout; empty,
/// with why in @a failure, when there is none.
std::string readDisplayNumber(int fd, std::string& failure)
{
  std::string number;
  const auto deadline = std::chrono::steady_clock::now() + kStartTimeout;
  for (;;)
  {
    const auto left =
      std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0)
    {
      failure = "it did not report a display within " + std::to_string(kStartTimeout.count()) + " s";
      break;
    }
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, int(left.count()));
    if (ready < 0 && errno == EINTR)
      continue;
    if (ready < 0)
    {
      failure = std::string("poll failed: ") + std::strerror(errno);
      break;
    }
    if (ready == 0)
      continue;
    char buffer[64];
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
    {
      failure = "it exited before accepting connections";
      break;
    }
    number.append(buffer, std::size_t(n));
    if (number.find('\n') != std::string::npos)
      break;
  }
  if (failure.empty())
  {
    number = number.substr(0, number.find('\n'));
    if (number.empty() || number.find_first_not_of("0123456789") != std::string::npos)
      failure = "it reported an unexpected display \"" + number + "\"";
  }
  return number;
}

struct State
{
  std::mutex mutex;
  pid_t pid = -1;                      ///< the private Xvfb, or -1
  std::string ownDisplay;              ///< ":N" of the private Xvfb
  std::string verified;                ///< a DISPLAY value found usable
  std::optional<std::string> previous; ///< DISPLAY before the private server (nullopt: unset)
  int objects = 0;

  ~State() { stopLocked(); }

  void stopLocked()
  {
    if (pid <= 0)
      return;
    stopProcess(pid);
    pid = -1;
    if (const char* current = std::getenv("DISPLAY"); current && current == ownDisplay)
    {
      if (previous)
        ::setenv("DISPLAY", previous->c_str(), 1);
      else
        ::unsetenv("DISPLAY");
    }
    if (verified == ownDisplay)
      verified.clear();
    ownDisplay.clear();
  }

  void startLocked(const std::string& why)
  {
    const std::string xvfb = findXvfb();
    if (xvfb.empty())
      throw std::runtime_error("Offscreen rendering needs an X server (" + why +
                               ") and Xvfb is not installed: " + kInstallHint + ".");

    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
      throw std::runtime_error(std::string("cannot start Xvfb: pipe failed: ") + std::strerror(errno));
    Fd readEnd(highFd(fds[0]));
    Fd writeEnd(highFd(fds[1]));
    char logName[] = "/tmp/caps-xvfb-XXXXXX";
    Fd log(::mkostemp(logName, O_CLOEXEC));
    if (log.get() < 0)
      throw std::runtime_error(std::string("cannot start Xvfb: cannot create its log: ") + std::strerror(errno));
    ::unlink(logName);
    log.reset(highFd(log.get()));
    Fd devNull(highFd(::open("/dev/null", O_RDWR | O_CLOEXEC)));

    // Everything the child needs is prepared here: between fork and exec it
    // may only make async-signal-safe calls.
    const char* argv[] = {"Xvfb",         "-displayfd", "3",   "-screen",  "0",
                          "2560x2048x24", "-nolisten",  "tcp", "-noreset", nullptr};
    const pid_t parent = ::getpid();
    const bool mainThread = ::gettid() == parent; // PDEATHSIG follows the forking thread
    sigset_t none;
    sigemptyset(&none);
    struct sigaction defaultAction
    {};
    defaultAction.sa_handler = SIG_DFL;

    const pid_t child = ::fork();
    if (child < 0)
      throw std::runtime_error(std::string("cannot start Xvfb: fork failed: ") + std::strerror(errno));
    if (child == 0)
    {
      if (mainThread)
      {
        ::prctl(PR_SET_PDEATHSIG, SIGTERM);
        if (::getppid() != parent)
          ::_exit(1);
      }
      ::sigprocmask(SIG_SETMASK, &none, nullptr);
      ::sigaction(SIGTERM, &defaultAction, nullptr);
      ::sigaction(SIGINT, &defaultAction, nullptr);
      ::sigaction(SIGPIPE, &defaultAction, nullptr);
      ::dup2(devNull.get(), 0);
      ::dup2(devNull.get(), 1);
      ::dup2(log.get(), 2);
      ::dup2(writeEnd.get(), 3);
      ::close_range(4, ~0U, 0);
      ::execv(xvfb.c_str(), const_cast<char* const*>(argv));
      ::_exit(127);
    }
    writeEnd.reset();

    std::string failure;
    const std::string number = readDisplayNumber(readEnd.get(), failure);
    if (!failure.empty())
    {
      stopProcess(child);
      const std::string output = readLog(log.get());
      throw std::runtime_error("Could not start Xvfb (" + xvfb + ") for offscreen rendering: " + failure +
                               (output.empty() ? std::string() : "; its output: " + output) +
                               ". If it keeps failing, run under xvfb-run -a.");
    }

    const std::string name = ":" + number;
    if (const auto problem = displayProblem(name.c_str()))
    {
      stopProcess(child);
      throw std::runtime_error("Xvfb started on " + name + " but " + *problem + "; " + kInstallHint + ".");
    }
    if (const char* current = std::getenv("DISPLAY"))
      previous = std::string(current);
    else
      previous.reset();
    pid = child;
    ownDisplay = name;
    verified = name;
    ::setenv("DISPLAY", name.c_str(), 1);
  }

  void ensureLocked()
  {
    const char* current = std::getenv("DISPLAY");
    const std::string display = current ? current : "";
    if (pid > 0)
    {
      if (hasExited(pid))
      { // the private server died: forget it and start another
        pid = -1;
        if (verified == ownDisplay)
          verified.clear();
        if (display == ownDisplay)
        {
          if (previous)
            ::setenv("DISPLAY", previous->c_str(), 1);
          else
            ::unsetenv("DISPLAY");
        }
        ownDisplay.clear();
        ensureLocked();
        return;
      }
      if (display == ownDisplay)
        return;
    }
    if (!display.empty() && display == verified)
      return;
    std::string why = "DISPLAY is not set";
    if (!display.empty())
    {
      const auto problem = displayProblem(display.c_str());
      if (!problem)
      {
        verified = display;
        return;
      }
      why = *problem;
    }
    if (pid > 0)
    { // DISPLAY was changed to something unusable: go back to ours
      ::setenv("DISPLAY", ownDisplay.c_str(), 1);
      return;
    }
    startLocked(why);
  }
};

State& state()
{
  static State s; // destroyed at exit: stops the private server
  return s;
}

} // namespace

OffscreenDisplay::OffscreenDisplay()
{
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.ensureLocked();
  ++s.objects;
}

OffscreenDisplay::~OffscreenDisplay()
{
  State& s = state();
  std::lock_guard lock(s.mutex);
  if (--s.objects == 0)
    s.stopLocked();
}

void OffscreenDisplay::ensure()
{
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.ensureLocked();
}

std::string OffscreenDisplay::display()
{
  State& s = state();
  std::lock_guard lock(s.mutex);
  return s.pid > 0 ? s.ownDisplay : s.verified;
}

bool OffscreenDisplay::ownsServer()
{
  State& s = state();
  std::lock_guard lock(s.mutex);
  return s.pid > 0;
}

int OffscreenDisplay::serverPid()
{
  State& s = state();
  std::lock_guard lock(s.mutex);
  return s.pid > 0 ? int(s.pid) : -1;
}

void OffscreenDisplay::shutdown()
{
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.stopLocked();
}

} // namespace caps::render
