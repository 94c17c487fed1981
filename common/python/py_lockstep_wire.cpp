// skillbus_native.decode_clock(data) -> lockstep_clock_t: the lockstep clock read from its
// bytes in one pass, into the generated Python classes (skillbus.lockstep_wire, which
// hands them over once with set_clock_types).
//
// Why: every Python participant decodes the clock of each frame it works in, and the
// clock lists every message of the frame before by sender and channel. In Python that was
// about 26 µs a frame in the demo's skill process and gripper device (docs/benchmarks.md),
// the string reads most of it. The rules are those of lockstep_wire's Python decoder
// (which stays, for SKILLBUS_NATIVE=0): the same fields, the same refusals as ValueError;
// tests/py/test_lockstep_wire.py runs its cases on both.
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <string>
#include <type_traits>
#include <utility>

#include "glue.hpp"

namespace skillbus::native {

namespace {

struct ClockTypes {
  std::string fingerprint;
  PyTypeObject* clock = nullptr;
  PyTypeObject* header = nullptr;
  PyTypeObject* count = nullptr;
};
ClockTypes types;

struct Names {
  PyObject *header, *frame, *sim_time_ns, *sender, *seq, *frame_period_ns, *num_participants, *participants, *counts,
      *num_counts, *stop, *stop_reason, *channel, *count;
};
Names names;

bool intern_names() {
  const char* all[] = {"header",       "frame",       "sim_time_ns", "sender",   "seq",  "frame_period_ns",
                       "num_participants", "participants", "counts", "num_counts", "stop", "stop_reason",
                       "channel",      "count"};
  PyObject** slots[] = {&names.header, &names.frame, &names.sim_time_ns, &names.sender, &names.seq,
                        &names.frame_period_ns, &names.num_participants, &names.participants, &names.counts,
                        &names.num_counts, &names.stop, &names.stop_reason, &names.channel, &names.count};
  for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i) {
    *slots[i] = PyUnicode_InternFromString(all[i]);
    if (!*slots[i]) return false;
  }
  return true;
}

// A reader over the message that remembers why it stopped: every read checks its bounds.
class Reader {
 public:
  Reader(const uint8_t* p, size_t n) : p_(p), n_(n) {}
  size_t at() const { return at_; }
  size_t size() const { return n_; }
  size_t left() const { return n_ - at_; }

  // A number as LCM writes it: big-endian, two's complement.
  template <class T>
  bool number(T& v) {
    if (left() < sizeof(T)) return cut();
    std::make_unsigned_t<T> u = 0;
    for (size_t i = 0; i < sizeof(T); ++i) u = static_cast<std::make_unsigned_t<T>>((uint64_t(u) << 8) | p_[at_ + i]);
    at_ += sizeof(T);
    v = static_cast<T>(u);
    return true;
  }
  // LCM's string: a length counting its NUL (at least 1), the bytes, the NUL; the last
  // byte is dropped whatever it is, and bytes that are not UTF-8 are replaced.
  PyObject* text(const char* what) {
    uint32_t n = 0;
    if (!number(n)) return nullptr;
    if (n < 1 || n > left()) {
      PyErr_Format(PyExc_ValueError, "%s cut short", what);
      return nullptr;
    }
    PyObject* s = PyUnicode_DecodeUTF8(reinterpret_cast<const char*>(p_ + at_), n - 1, "replace");
    at_ += n;
    return s;
  }

 private:
  bool cut() {
    PyErr_SetString(PyExc_ValueError, "a lockstep_clock_t cut short");
    return false;
  }
  const uint8_t* p_;
  size_t n_;
  size_t at_ = 0;
};

// Sets `name` on `o` to `value`, which it steals; false with an error set (a null value:
// the error of what made it).
bool put(PyObject* o, PyObject* name, PyObject* value) {
  if (!value) return false;
  const int r = PyObject_SetAttr(o, name, value);
  Py_DECREF(value);
  return r == 0;
}

// A new `t` with each name set to its value; every value is stolen, whatever fails.
PyObject* make(PyTypeObject* t, std::initializer_list<std::pair<PyObject*, PyObject*>> fields) {
  PyObject* o = t->tp_alloc(t, 0);
  bool ok = o != nullptr;
  for (const auto& [name, value] : fields) {
    if (ok) {
      ok = put(o, name, value);
    } else {
      Py_XDECREF(value);
    }
  }
  if (!ok) Py_CLEAR(o);
  return o;
}

PyObject* read_header(Reader& r) {
  int64_t frame = 0, sim_time = 0;
  int32_t seq = 0;
  if (!r.number(frame) || !r.number(sim_time)) return nullptr;
  PyObject* sender = r.text("a header");
  if (!sender || !r.number(seq)) {
    Py_XDECREF(sender);
    return nullptr;
  }
  return make(types.header, {{names.sender, sender}, {names.frame, PyLong_FromLongLong(frame)},
                             {names.sim_time_ns, PyLong_FromLongLong(sim_time)}, {names.seq, PyLong_FromLong(seq)}});
}

// `n` items read by `one` into a new list; null with an error set.
template <class One>
PyObject* read_list(int32_t n, One one) {
  PyObject* list = PyList_New(n);
  if (!list) return nullptr;
  for (int32_t i = 0; i < n; ++i) {
    PyObject* item = one();
    if (!item) {
      Py_DECREF(list);
      return nullptr;
    }
    PyList_SET_ITEM(list, i, item);
  }
  return list;
}

PyObject* read_count(Reader& r) {
  PyObject* sender = r.text("a string");
  PyObject* channel = sender ? r.text("a string") : nullptr;
  int64_t frame = 0;
  int32_t count = 0;
  if (!channel || !r.number(frame) || !r.number(count)) {
    Py_XDECREF(sender);
    Py_XDECREF(channel);
    return nullptr;
  }
  return make(types.count, {{names.sender, sender}, {names.channel, channel},
                            {names.frame, PyLong_FromLongLong(frame)}, {names.count, PyLong_FromLong(count)}});
}

// A count read before its items: at most as many as bytes are left (each item takes more).
bool plausible(int32_t n, const Reader& r, const char* what) {
  if (n < 0 || static_cast<size_t>(n) > r.left()) {
    PyErr_Format(PyExc_ValueError, "%d %s", n, what);
    return false;
  }
  return true;
}

PyObject* decode(const uint8_t* p, size_t n);

PyObject* decode_clock(PyObject*, PyObject* data) {
  if (!types.clock) {
    PyErr_SetString(PyExc_RuntimeError, "decode_clock: set_clock_types was not called");
    return nullptr;
  }
  // (bytes as the bus hands them, or a bytearray; anything else is no clock, as in Python)
  if (PyBytes_Check(data))
    return decode(reinterpret_cast<const uint8_t*>(PyBytes_AS_STRING(data)), static_cast<size_t>(PyBytes_GET_SIZE(data)));
  if (PyByteArray_Check(data))
    return decode(reinterpret_cast<const uint8_t*>(PyByteArray_AS_STRING(data)),
                  static_cast<size_t>(PyByteArray_GET_SIZE(data)));
  PyErr_Format(PyExc_ValueError, "not a lockstep_clock_t (%.100s, not bytes)", Py_TYPE(data)->tp_name);
  return nullptr;
}

PyObject* decode(const uint8_t* p, size_t n) {
  if (n < 8 || std::memcmp(p, types.fingerprint.data(), 8) != 0) {
    PyErr_SetString(PyExc_ValueError, "not a lockstep_clock_t (its fingerprint differs)");
    return nullptr;
  }
  Reader r(p + 8, n - 8);
  PyObject* clock = types.clock->tp_alloc(types.clock, 0);
  if (!clock) return nullptr;
  int64_t period = 0;
  int32_t count = 0;
  uint8_t stop = 0;
  bool ok = put(clock, names.header, read_header(r)) && r.number(period) && r.number(count) &&
            plausible(count, r, "participants") && put(clock, names.frame_period_ns, PyLong_FromLongLong(period)) &&
            put(clock, names.num_participants, PyLong_FromLong(count)) &&
            put(clock, names.participants, read_list(count, [&] { return r.text("a string"); })) && r.number(count) &&
            plausible(count, r, "counts") && put(clock, names.counts, read_list(count, [&] { return read_count(r); })) &&
            put(clock, names.num_counts, PyLong_FromLong(count)) && r.number(stop) &&
            put(clock, names.stop, PyBool_FromLong(stop != 0)) && put(clock, names.stop_reason, r.text("a string"));
  if (ok && r.left() != 0) {
    PyErr_Format(PyExc_ValueError, "a lockstep_clock_t with %zu bytes after its end", r.left());
    ok = false;
  }
  if (!ok) {
    Py_DECREF(clock);
    return nullptr;
  }
  return clock;
}

PyObject* set_clock_types(PyObject*, PyObject* args) {
  PyObject *fingerprint = nullptr, *clock = nullptr, *header = nullptr, *count = nullptr;
  if (!PyArg_ParseTuple(args, "SO!O!O!", &fingerprint, &PyType_Type, &clock, &PyType_Type, &header, &PyType_Type,
                        &count))
    return nullptr;
  if (PyBytes_GET_SIZE(fingerprint) != 8) {
    PyErr_SetString(PyExc_ValueError, "set_clock_types: a fingerprint of 8 bytes needed");
    return nullptr;
  }
  types.fingerprint.assign(PyBytes_AS_STRING(fingerprint), 8);
  // (kept for the module's life: the generated classes live as long)
  Py_INCREF(clock);
  Py_INCREF(header);
  Py_INCREF(count);
  Py_XDECREF(types.clock);
  Py_XDECREF(types.header);
  Py_XDECREF(types.count);
  types.clock = reinterpret_cast<PyTypeObject*>(clock);
  types.header = reinterpret_cast<PyTypeObject*>(header);
  types.count = reinterpret_cast<PyTypeObject*>(count);
  Py_RETURN_NONE;
}

PyMethodDef methods[] = {
    {"decode_clock", decode_clock, METH_O,
     "decode_clock(data) -> lockstep_clock_t: the clock in `data`, ValueError when it is none "
     "(skillbus.lockstep_wire)."},
    {"set_clock_types", set_clock_types, METH_VARARGS,
     "set_clock_types(fingerprint, clock_t, header_t, channel_count_t): the classes decode_clock fills."},
    {nullptr, nullptr, 0, nullptr}};

}  // namespace

bool add_lockstep_wire(PyObject* module) { return intern_names() && PyModule_AddFunctions(module, methods) == 0; }

}  // namespace skillbus::native
