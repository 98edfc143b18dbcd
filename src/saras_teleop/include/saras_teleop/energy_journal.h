/**
 * @file energy_journal.h
 * @brief The last energy of a tank, kept in a memory-mapped file so that a restarted tank resumes
 *        with exactly the energy it had when its process died, never more (ROS-agnostic).
 *
 * The file (on a RAM file system such as /dev/shm: no disk I/O) holds a magic number, a session
 * token, the energy [J] and a write counter. record() is one store into the mapping (no system call,
 * no allocation: safe in the control loop); the kernel keeps the page when the process dies, so a
 * respawned process reads the value of the last completed step. A journal is valid for a restart only
 * with the token of the same session (the caller keeps the token where a restart finds it, e.g. the
 * ROS parameter server of the running master); a journal of another session, a missing or a corrupt
 * file gives NaN, and the caller then starts empty.
 */
#ifndef SARAS_TELEOP_ENERGY_JOURNAL_H
#define SARAS_TELEOP_ENERGY_JOURNAL_H

#include <cstdint>
#include <string>

namespace saras_teleop
{
class EnergyJournal
{
public:
  EnergyJournal() = default;
  ~EnergyJournal();
  EnergyJournal(const EnergyJournal&) = delete;
  EnergyJournal& operator=(const EnergyJournal&) = delete;

  /**
   * Map @p path (created if missing). @return the energy [J] the file holds for @p token, NaN when
   * the file is new, of another session or corrupt. After open() the journal belongs to @p token.
   * @throws std::runtime_error naming the file if it cannot be created or mapped.
   */
  double open(const std::string& path, std::uint64_t token);

  /// Store @p energy [J] (no-op before open()).
  void record(double energy) noexcept;

  bool isOpen() const { return slot_ != nullptr; }
  const std::string& path() const { return path_; }

  /// A fresh random session token (never 0).
  static std::uint64_t newToken();

private:
  struct Slot;
  Slot* slot_ = nullptr;
  std::string path_;
};

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_ENERGY_JOURNAL_H
