#include "skillbus/wm/ontology_files.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

#include "skillbus/wm/model.hpp"

namespace skillbus::wm {

namespace fs = std::filesystem;

namespace {

bool is_ontology_file(const fs::path& p) {
  const std::string ext = p.extension().string();
  return ext == ".owl" || ext == ".ttl" || ext == ".rdf";
}

// (an empty folder: an error for --ontology, which would load nothing; a library may be empty)
std::vector<fs::path> expand(const std::string& path, bool may_be_empty = false) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return {fs::path(path)};
  std::vector<fs::path> out;
  for (fs::recursive_directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec) && is_ontology_file(it->path())) out.push_back(it->path());
  if (ec) throw WmError("cannot list the ontology folder " + path + ": " + ec.message());
  std::sort(out.begin(), out.end());
  if (out.empty() && !may_be_empty) throw WmError("the ontology folder " + path + " has no .owl, .ttl or .rdf file");
  return out;
}

std::string read(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  if (!f) throw WmError("cannot read the ontology " + p.string());
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

std::vector<Triple> parse_file(const fs::path& file, Prefixes& prefixes) {
  std::error_code ec;
  const fs::path abs = fs::absolute(file, ec);
  return parse_rdf(read(file), prefixes, file.string(), "file://" + (ec ? file : abs).string());
}

}  // namespace

OntologyLoad load_ontology_files(Ontology& ontology, Prefixes& prefixes, const std::vector<std::string>& paths) {
  OntologyLoad out;
  for (const auto& path : paths) {
    for (const auto& file : expand(path)) {
      std::vector<Triple> triples = parse_file(file, prefixes);
      ontology.add_triples(triples, prefixes);
      append_apart(out.triples, triples);  // (written as one document later: its blank nodes kept apart)
      out.files.push_back(file.string());
    }
  }
  out.missing_imports = ontology.missing_imports();
  return out;
}

OntologyLibrary::OntologyLibrary(const std::vector<std::string>& paths) {
  for (const auto& path : paths) {
    for (const auto& file : expand(path, true)) {
      Prefixes scratch;  // (the library's prefixes count only once a file is loaded)
      for (const auto& t : parse_file(file, scratch))
        if (t.s.kind == Term::Iri && t.p.value == kRdfType && t.o.value == "http://www.w3.org/2002/07/owl#Ontology")
          files_.emplace(ontology_iri(t.s.value), file.string());  // (the first file that declares it)
    }
  }
}

OntologyLoad OntologyLibrary::resolve(Ontology& ontology, Prefixes& prefixes) const {
  OntologyLoad out;
  std::set<std::string> loaded;  // (a file is read once, whatever it declares)
  for (;;) {
    std::vector<std::string> found;
    out.missing_imports.clear();
    for (const auto& iri : ontology.missing_imports()) {
      auto it = files_.find(iri);
      if (it == files_.end())
        out.missing_imports.push_back(iri);
      else if (loaded.insert(it->second).second)
        found.push_back(it->second);
    }
    if (found.empty()) return out;
    for (const auto& file : found) {
      std::vector<Triple> triples = parse_file(file, prefixes);
      ontology.add_triples(triples, prefixes);
      append_apart(out.triples, triples);
      out.files.push_back(file);
    }
  }
}

}  // namespace skillbus::wm
