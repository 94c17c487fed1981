// Ontologies from files and folders, as SkiROS2 keeps them: OWL in RDF/XML or Turtle; a
// folder means every *.owl, *.ttl and *.rdf in it and below, in path order (SkiROS2 loads
// its owl/ folder so). Used by the world model server and the skill manager alike.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "skillbus/wm/ontology.hpp"

namespace skillbus::wm {

struct OntologyLoad {
  std::vector<std::string> files;            // read, in order
  std::vector<std::string> missing_imports;  // owl:imports that no file read declares
  std::vector<Triple> triples;               // all of them, for those who ask the server
};

// Throws WmError naming the file (and line) that cannot be read or parsed.
OntologyLoad load_ontology_files(Ontology& ontology, Prefixes& prefixes, const std::vector<std::string>& paths);

// Ontology files that are not loaded at start but found when something loaded imports
// them (`wm_server --ontology-library`): each file is known by the owl:Ontology IRI it
// declares. A scene that says `owl:imports <…/robot.owl>` is loaded with that ontology,
// and with the ontologies that one imports in turn.
class OntologyLibrary {
 public:
  OntologyLibrary() = default;
  // Reads every file (folders as for --ontology) to learn what it declares; throws WmError
  // naming a file that cannot be read or parsed.
  explicit OntologyLibrary(const std::vector<std::string>& paths);
  // Loads into `ontology` each library file that declares an ontology `ontology` imports
  // but has not loaded, until none is left to find. `missing_imports` of the result: the
  // imports neither loaded nor in the library.
  OntologyLoad resolve(Ontology& ontology, Prefixes& prefixes) const;
  size_t size() const { return files_.size(); }

 private:
  std::map<std::string, std::string> files_;  // ontology IRI (ontology_iri form) -> file
};

}  // namespace skillbus::wm
