// Ontologies from files and folders, as SkiROS2 keeps them: OWL in RDF/XML or Turtle; a
// folder means every *.owl, *.ttl and *.rdf in it and below, in path order (SkiROS2 loads
// its owl/ folder so). Used by the world model server and the skill manager alike.
#pragma once

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

}  // namespace skillbus::wm
