#pragma once
// Work that only some ranks do between collectives (making folders, writing files) runs through
// agreed(): an exception on any rank becomes the same OutputPathError on every rank.
#include <Teuchos_Comm.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <exception>
#include <filesystem>
#include <string>

#include "perinox/evaluator/LowestRankMessage.hpp"
#include "perinox/io/OutputFolder.hpp"

namespace perinox {

/// Runs f on every rank (f may do nothing on some). If it throws on any rank, every rank throws
/// the same OutputPathError (the sentence of the lowest failing rank) once all have finished f,
/// so no rank is left waiting in a collective for one that threw. For work done by some ranks
/// only between collectives: writing files, making folders.
template <class F>
void agreed(const Teuchos::Comm<int>& comm, F&& f) {
  std::string msg;
  try {
    f();
  } catch (const std::filesystem::filesystem_error& e) {
    msg = e.code().message() + " at '" + e.path1().string() + "'";
  } catch (const std::exception& e) {
    msg = e.what();
    if (msg.empty()) msg = "unknown error";
  }
  const int size = comm.getSize();
  int first = size;
  msg = lowestRankMessage(comm, msg, &first);
  if (first == size) return;
  if (msg.rfind("--", 0) == 0) throw OutputPathError(msg);  // already names its option
  throw OutputPathError("writing the results failed" + (size > 1 ? " on rank " + std::to_string(first) : std::string()) +
                        ": " + msg);
}

}  // namespace perinox
