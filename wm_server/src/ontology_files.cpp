#include "skillbus/wm/ontology_files.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "skillbus/wm/model.hpp"

namespace skillbus::wm {

namespace fs = std::filesystem;

namespace {

bool is_ontology_file(const fs::path& p) {
  const std::string ext = p.extension().string();
  return ext == ".owl" || ext == ".ttl" || ext == ".rdf";
}

std::vector<fs::path> expand(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return {fs::path(path)};
  std::vector<fs::path> out;
  for (fs::recursive_directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec) && is_ontology_file(it->path())) out.push_back(it->path());
  if (ec) throw WmError("cannot list the ontology folder " + path + ": " + ec.message());
  std::sort(out.begin(), out.end());
  if (out.empty()) throw WmError("the ontology folder " + path + " has no .owl, .ttl or .rdf file");
  return out;
}

std::string read(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  if (!f) throw WmError("cannot read the ontology " + p.string());
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

}  // namespace

OntologyLoad load_ontology_files(Ontology& ontology, Prefixes& prefixes, const std::vector<std::string>& paths) {
  OntologyLoad out;
  for (const auto& path : paths) {
    for (const auto& file : expand(path)) {
      std::error_code ec;
      const fs::path abs = fs::absolute(file, ec);
      std::vector<Triple> triples = parse_rdf(read(file), prefixes, file.string(), "file://" + (ec ? file : abs).string());
      ontology.add_triples(triples, prefixes);
      out.triples.insert(out.triples.end(), triples.begin(), triples.end());
      out.files.push_back(file.string());
    }
  }
  out.missing_imports = ontology.missing_imports();
  return out;
}

}  // namespace skillbus::wm
