#include "saras_teleop/energy_journal.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>

namespace saras_teleop
{
struct EnergyJournal::Slot
{
  std::uint64_t magic;
  std::atomic<std::uint64_t> token;
  std::atomic<double> energy;
  std::atomic<std::uint64_t> writes;
};

namespace
{
constexpr std::uint64_t kMagic = 0x53415241534a524eULL;  // "SARASJRN"
}

EnergyJournal::~EnergyJournal()
{
  if (slot_)
    munmap(slot_, sizeof(Slot));
}

double EnergyJournal::open(const std::string& path, std::uint64_t token)
{
  if (slot_)
    throw std::runtime_error("energy journal " + path_ + " is already open");
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (fd < 0)
    throw std::runtime_error("energy journal " + path + ": " + std::strerror(errno));
  struct stat st;
  const bool sized = fstat(fd, &st) == 0 && st.st_size == static_cast<off_t>(sizeof(Slot));
  // a file of another size is not a journal: emptied, then sized (zeroed) for one slot
  void* m = MAP_FAILED;
  if (sized || (ftruncate(fd, 0) == 0 && ftruncate(fd, sizeof(Slot)) == 0))
    m = mmap(nullptr, sizeof(Slot), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  const std::string why = std::strerror(errno);
  ::close(fd);
  if (m == MAP_FAILED)
    throw std::runtime_error("energy journal " + path + ": " + why);
  slot_ = static_cast<Slot*>(m);
  path_ = path;
  double last = std::numeric_limits<double>::quiet_NaN();
  if (sized && slot_->magic == kMagic && slot_->token.load() == token && slot_->writes.load() > 0)
  {
    const double e = slot_->energy.load();
    if (std::isfinite(e) && e >= 0.0)
      last = e;
  }
  if (std::isnan(last))
  {
    // from now on this session owns the file; nothing is valid until the first record()
    slot_->writes.store(0);
    slot_->token.store(token);
    slot_->magic = kMagic;
  }
  return last;
}

void EnergyJournal::record(double energy) noexcept
{
  if (!slot_)
    return;
  slot_->energy.store(energy, std::memory_order_relaxed);
  slot_->writes.fetch_add(1, std::memory_order_release);
}

std::uint64_t EnergyJournal::newToken()
{
  std::random_device rd;
  std::uint64_t t = 0;
  while (t == 0)
    t = (static_cast<std::uint64_t>(rd()) << 32) ^ rd();
  return t;
}

}  // namespace saras_teleop
