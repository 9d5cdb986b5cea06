#pragma once
// Agreeing on a failure across ranks: the ranks that failed pass their sentence, the others an
// empty one, and every rank gets the same answer, so all of them throw (or none does) and no rank
// is left waiting in a later collective for one that stopped.
#include <Teuchos_Comm.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <stdexcept>
#include <string>

#include "perinox/model/Model.hpp"

namespace perinox {

/// The message of the lowest rank whose `msg` is not empty, on every rank; "" when none is.
/// Collective over comm. `rank`, if given, receives that rank (comm.getSize() when none failed).
inline std::string lowestRankMessage(const Teuchos::Comm<int>& comm, std::string msg, int* rank = nullptr) {
  const int size = comm.getSize();
  int mine = msg.empty() ? size : comm.getRank(), first = size;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, mine, Teuchos::outArg(first));
  if (rank) *rank = first;
  if (first == size) return "";
  int length = static_cast<int>(msg.size());
  Teuchos::broadcast(comm, first, Teuchos::outArg(length));
  msg.resize(static_cast<std::size_t>(length));
  if (length > 0) Teuchos::broadcast(comm, first, length, msg.data());
  return msg;
}

/// Runs f on every rank; an E (a std::exception with a sentence) thrown on any rank is thrown as E
/// on every rank, with the lowest failing rank's sentence, once all have run f: for work that
/// differs between ranks (each reads its part of a file) before the next collective.
template <class E, class F>
void throwAgreed(const Teuchos::Comm<int>& comm, F&& f) {
  std::string msg;
  try {
    f();
  } catch (const E& e) {
    msg = e.what();
    if (msg.empty()) msg = "unknown error";
  }
  msg = lowestRankMessage(comm, msg);
  if (!msg.empty()) throw E(msg);
}

/// Runs f on every rank, for rank-local set-up work (a rank's families, its model) before the next
/// collective. If f throws on any rank, every rank throws once all have run f, with the lowest
/// failing rank's sentence: std::invalid_argument when that rank's error was about the input
/// (std::invalid_argument, or an EvaluationError such as a singular shape tensor), otherwise
/// std::runtime_error. Without this, a rank that refuses alone leaves the others waiting.
template <class F>
void agreeOnSetUp(const Teuchos::Comm<int>& comm, F&& f) {
  std::string msg;
  try {
    f();
  } catch (const std::invalid_argument& e) {
    msg = std::string("I") + e.what();
  } catch (const EvaluationError& e) {
    msg = std::string("I") + e.what();
  } catch (const std::exception& e) {
    msg = std::string("R") + e.what();
  }
  msg = lowestRankMessage(comm, msg);
  if (msg.empty()) return;
  if (msg[0] == 'I') throw std::invalid_argument(msg.substr(1));
  throw std::runtime_error(msg.substr(1));
}

}  // namespace perinox
