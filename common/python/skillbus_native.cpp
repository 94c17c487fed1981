// skillbus_native: the Python extension module of skillbus's C++ hot paths.
//
//   QuietFrames(fd, clock_channel, ack_channel, ack_url, name, keys, identity, policy_text)
//     .set_subscribed(channels)
//     .wait(timeout_s, master, last_acked, last_sim_time, last_ack, running)
//         -> (datagram | None, (ip, port) | None, acked, last_acked, last_sim_time,
//             last_ack, running, resends)
//     .rejected() -> {reason: count}     .lost_sends() -> int
//
// See quiet_frames.hpp; the Python side is LockstepParticipant (py_skills/skillbus/
// lockstep.py). Errors raise RuntimeError with the C++ message.
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <cstring>
#include <memory>
#include <set>
#include <string>

#include "quiet_frames.hpp"

namespace {

using skillbus::native::Datagram;
using skillbus::native::QuietConfig;
using skillbus::native::QuietFrames;
using skillbus::native::QuietState;

struct PyQuietFrames {
  PyObject_HEAD
  QuietFrames* core;
};

bool bytes_of(PyObject* o, skillbus::Bytes& out, const char* what) {
  char* p = nullptr;
  Py_ssize_t n = 0;
  if (PyBytes_AsStringAndSize(o, &p, &n) != 0) {
    PyErr_Format(PyExc_TypeError, "%s: bytes needed", what);
    return false;
  }
  out.assign(reinterpret_cast<uint8_t*>(p), reinterpret_cast<uint8_t*>(p) + n);
  return true;
}

int quiet_init(PyObject* self_obj, PyObject* args, PyObject*) {
  auto* self = reinterpret_cast<PyQuietFrames*>(self_obj);
  QuietConfig cfg;
  const char *clock, *ack, *url, *name, *identity, *policy;
  PyObject* keys;
  if (!PyArg_ParseTuple(args, "issssOss", &cfg.fd, &clock, &ack, &url, &name, &keys, &identity, &policy))
    return -1;
  cfg.clock_channel = clock, cfg.ack_channel = ack, cfg.ack_url = url, cfg.name = name;
  cfg.identity = identity, cfg.policy_text = policy;
  PyObject* it = PyObject_GetIter(keys);
  if (!it) return -1;
  while (PyObject* k = PyIter_Next(it)) {
    skillbus::Bytes key;
    const bool ok = bytes_of(k, key, "a key");
    Py_DECREF(k);
    if (!ok) {
      Py_DECREF(it);
      return -1;
    }
    cfg.keys.push_back(std::move(key));
  }
  Py_DECREF(it);
  if (PyErr_Occurred()) return -1;
  try {
    delete self->core;
    self->core = new QuietFrames(std::move(cfg));
  } catch (const std::exception& e) {
    self->core = nullptr;
    PyErr_SetString(PyExc_RuntimeError, e.what());
    return -1;
  }
  return 0;
}

void quiet_dealloc(PyObject* self_obj) {
  auto* self = reinterpret_cast<PyQuietFrames*>(self_obj);
  delete self->core;
  Py_TYPE(self_obj)->tp_free(self_obj);
}

QuietFrames* core_of(PyObject* self_obj) {
  auto* core = reinterpret_cast<PyQuietFrames*>(self_obj)->core;
  if (!core) PyErr_SetString(PyExc_RuntimeError, "QuietFrames is not initialised");
  return core;
}

PyObject* quiet_set_subscribed(PyObject* self_obj, PyObject* channels) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  std::set<std::string> out;
  PyObject* it = PyObject_GetIter(channels);
  if (!it) return nullptr;
  while (PyObject* c = PyIter_Next(it)) {
    const char* s = PyUnicode_AsUTF8(c);
    Py_DECREF(c);
    if (!s) {
      Py_DECREF(it);
      return nullptr;
    }
    out.insert(s);
  }
  Py_DECREF(it);
  if (PyErr_Occurred()) return nullptr;
  core->set_subscribed(std::move(out));
  Py_RETURN_NONE;
}

PyObject* quiet_wait(PyObject* self_obj, PyObject* args) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  double timeout_s;
  const char* master;
  long long last_acked, last_sim_time;
  PyObject *last_ack, *running;
  if (!PyArg_ParseTuple(args, "dsLLSS", &timeout_s, &master, &last_acked, &last_sim_time, &last_ack, &running))
    return nullptr;
  QuietState s;
  s.master = master;
  s.last_acked = last_acked;
  s.last_sim_time = last_sim_time;
  if (!bytes_of(last_ack, s.last_ack, "last_ack")) return nullptr;
  if (PyBytes_GET_SIZE(running) != static_cast<Py_ssize_t>(s.running.size())) {
    PyErr_SetString(PyExc_ValueError, "running: a 32-byte digest needed");
    return nullptr;
  }
  std::memcpy(s.running.data(), PyBytes_AS_STRING(running), s.running.size());
  Datagram d;
  bool got = false;
  std::string error;
  Py_BEGIN_ALLOW_THREADS
  try {
    got = core->wait(s, static_cast<int>(timeout_s * 1000 + 0.999), d);
  } catch (const std::exception& e) {
    error = e.what();
  }
  Py_END_ALLOW_THREADS
  if (!error.empty()) {
    PyErr_SetString(PyExc_RuntimeError, error.c_str());
    return nullptr;
  }
  PyObject* datagram = Py_None;
  PyObject* sender = Py_None;
  if (got) {
    datagram = PyBytes_FromStringAndSize(reinterpret_cast<const char*>(d.data.data()), Py_ssize_t(d.data.size()));
    sender = Py_BuildValue("(si)", d.sender_ip.c_str(), d.sender_port);
  } else {
    Py_INCREF(datagram);
    Py_INCREF(sender);
  }
  return Py_BuildValue("(NNLLLy#y#L)", datagram, sender, static_cast<long long>(s.acked),
                       static_cast<long long>(s.last_acked), static_cast<long long>(s.last_sim_time),
                       reinterpret_cast<const char*>(s.last_ack.data()), Py_ssize_t(s.last_ack.size()),
                       reinterpret_cast<const char*>(s.running.data()), Py_ssize_t(s.running.size()),
                       static_cast<long long>(s.resends));
}

PyObject* quiet_rejected(PyObject* self_obj, PyObject*) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  PyObject* out = PyDict_New();
  if (!out) return nullptr;
  if (const auto* stats = core->stats()) {
    for (const auto& [reason, count] : stats->rejected) {
      PyObject* v = PyLong_FromUnsignedLongLong(count);
      if (!v || PyDict_SetItemString(out, reason.c_str(), v) != 0) {
        Py_XDECREF(v);
        Py_DECREF(out);
        return nullptr;
      }
      Py_DECREF(v);
    }
  }
  return out;
}

PyObject* quiet_lost_sends(PyObject* self_obj, PyObject*) {
  QuietFrames* core = core_of(self_obj);
  return core ? PyLong_FromUnsignedLongLong(core->lost_sends()) : nullptr;
}

PyMethodDef quiet_methods[] = {
    {"set_subscribed", quiet_set_subscribed, METH_O, "The channels whose announced messages give a frame work."},
    {"wait", quiet_wait, METH_VARARGS, "Acks quiet frames until a datagram for Python comes or the timeout."},
    {"rejected", quiet_rejected, METH_NOARGS, "Clocks dropped by authentication, by reason (cumulative)."},
    {"lost_sends", quiet_lost_sends, METH_NOARGS, "Acks the network refused to send."},
    {nullptr, nullptr, 0, nullptr}};

PyTypeObject quiet_type = {PyVarObject_HEAD_INIT(nullptr, 0)};

PyModuleDef module_def = {PyModuleDef_HEAD_INIT, "skillbus_native", "skillbus's C++ hot paths for Python.", -1,
                          nullptr};

}  // namespace

PyMODINIT_FUNC PyInit_skillbus_native() {
  quiet_type.tp_name = "skillbus_native.QuietFrames";
  quiet_type.tp_basicsize = sizeof(PyQuietFrames);
  quiet_type.tp_flags = Py_TPFLAGS_DEFAULT;
  quiet_type.tp_doc = "Acks a Python lockstep participant's quiet frames without the interpreter.";
  quiet_type.tp_new = PyType_GenericNew;
  quiet_type.tp_init = quiet_init;
  quiet_type.tp_dealloc = quiet_dealloc;
  quiet_type.tp_methods = quiet_methods;
  if (PyType_Ready(&quiet_type) < 0) return nullptr;
  PyObject* m = PyModule_Create(&module_def);
  if (!m) return nullptr;
  Py_INCREF(&quiet_type);
  if (PyModule_AddObject(m, "QuietFrames", reinterpret_cast<PyObject*>(&quiet_type)) < 0) {
    Py_DECREF(&quiet_type);
    Py_DECREF(m);
    return nullptr;
  }
  return m;
}
