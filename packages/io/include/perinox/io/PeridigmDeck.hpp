#pragma once
// Peridigm input decks read as scenes: `perinox run deck.xml` (or deck.yaml) runs a Peridigm deck
// of the elastic or elastic-plastic correspondence kind as it is. The deck is translated into a
// scene (a Teuchos list the scene reader then checks like any other); what cannot be translated
// into the same model is refused with one sentence naming the deck's key. docs/peridigm.md lists
// the translation key by key.
#include <Teuchos_ParameterList.hpp>

#include <string>

namespace perinox {

/// Whether a list read from a scene file is a Peridigm deck rather than a scene: it has
/// Peridigm's `Materials` or `Compute Class Parameters` lists, or a `Discretization` with an
/// `Input Mesh File` (no scene key has those names).
bool isPeridigmDeck(const Teuchos::ParameterList& pl);

/// The scene a Peridigm deck makes.
struct PeridigmScene {
  Teuchos::ParameterList scene;
  /// The deck asks for Verlet (explicit dynamics): it runs only if every displacement is
  /// prescribed (then the motion is kinematic and the load steps are the time steps); the
  /// scene reader checks that once the mesh is read.
  bool kinematicOnly = false;
};

/// Translates the deck read from `deckPath` (its mesh and node-set files are relative to the
/// deck's folder; the scene names them by absolute paths, so it runs from anywhere). Throws
/// SceneError "<deckPath>: <one sentence naming the key>" for anything it cannot translate.
PeridigmScene sceneFromPeridigmDeck(const Teuchos::ParameterList& deck, const std::string& deckPath);

}  // namespace perinox
