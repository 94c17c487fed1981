// skillbus_native.QuietFrames: the CPython glue of QuietFrames (quiet_frames.hpp).
//
//   QuietFrames(fd, clock_channel, ack_channel, ack_url, name, opener, signing_key, identity)
//       opener: the bus's skillbus_native.Opener, or None on an open bus (then signing_key
//       is None too); identity: bytes
//     .set_subscribed(channels)
//     .set_latest_only(channels)       (subscribed channels whose handler keeps the newest)
//     .set_finger_watch(channel, width_lo_m, width_hi_m, force_lo_n, force_hi_n, position_lo_um,
//                       position_hi_um, target_um, apart_um)   (finger_watch.hpp)
//     .clear_watches()
//     .wait(timeout_s, master, last_acked, last_sim_time, last_ack, running
//           [, quiet_through_frame, quiet_before_ns])
//         -> (datagram | None, (ip, port) | None, acked, last_acked, last_sim_time,
//             last_ack, running, resends, handed)
//         handed: [(kind, channel, payload)]: kind 0 the newest message of a channel in
//         frames the core acked, 1 the clock of a frame it was collecting, 2 a message
//         held for a frame Python takes (payloads verified)
//     .hold(channel, payload, last_acked)   (a verified latest-only message Python held)
//     .release() -> handed
//     .counts() -> {"ok": messages it verified, reason: messages it dropped}  (cumulative)
//     .verdicts() -> {(reason or "ok", channel): count}  (cumulative)
//     .latest_stats() -> {"stale": n, "duplicates": n}  (cumulative)
//     .lost_sends() -> int
//
// The Python side is skillbus.quiet_frames and LockstepParticipant (py_skills/skillbus/).
// A socket error raises OSError; anything else RuntimeError with the C++ message.
#include <algorithm>
#include <cstring>
#include <set>
#include <string>
#include <system_error>

#include "glue.hpp"
#include "quiet_frames.hpp"

namespace skillbus::native {

namespace {

struct PyQuietFrames {
  PyObject_HEAD
  QuietFrames* core;
};

int quiet_init(PyObject* self_obj, PyObject* args, PyObject*) {
  auto* self = reinterpret_cast<PyQuietFrames*>(self_obj);
  if (self->core) {
    PyErr_SetString(PyExc_RuntimeError, "a QuietFrames is initialised once");
    return -1;
  }
  QuietConfig cfg;
  PyObject *clock, *ack, *url, *name, *opener, *key, *identity;
  if (!PyArg_ParseTuple(args, "iOOOOOOS", &cfg.fd, &clock, &ack, &url, &name, &opener, &key, &identity)) return -1;
  Bytes id;
  if (!utf8_of(clock, cfg.clock_channel, "clock_channel") || !utf8_of(ack, cfg.ack_channel, "ack_channel") ||
      !utf8_of(url, cfg.ack_url, "ack_url") || !utf8_of(name, cfg.name, "name") || !bytes_of(identity, id, "identity"))
    return -1;
  cfg.identity.assign(id.begin(), id.end());
  if (opener != Py_None) {
    cfg.opener = opener_of(opener);
    if (!cfg.opener) {
      PyErr_SetString(PyExc_TypeError, "opener: a skillbus_native.Opener or None needed");
      return -1;
    }
    if (!bytes_of(key, cfg.signing_key, "signing_key")) return -1;
  }
  try {
    self->core = new QuietFrames(std::move(cfg));
  } catch (const std::exception& e) {
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
    std::string s;
    const bool ok = utf8_of(c, s, "a channel");
    Py_DECREF(c);
    if (!ok) {
      Py_DECREF(it);
      return nullptr;
    }
    out.insert(std::move(s));
  }
  Py_DECREF(it);
  if (PyErr_Occurred()) return nullptr;
  core->set_subscribed(std::move(out));
  Py_RETURN_NONE;
}

bool set_count(PyObject* dict, const char* key, uint64_t n) {
  PyObject* v = PyLong_FromUnsignedLongLong(n);
  const bool ok = v && PyDict_SetItemString(dict, key, v) == 0;
  Py_XDECREF(v);
  return ok;
}

PyObject* quiet_set_latest_only(PyObject* self_obj, PyObject* channels) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  std::set<std::string> out;
  PyObject* it = PyObject_GetIter(channels);
  if (!it) return nullptr;
  while (PyObject* c = PyIter_Next(it)) {
    std::string s;
    const bool ok = utf8_of(c, s, "a channel");
    Py_DECREF(c);
    if (!ok) {
      Py_DECREF(it);
      return nullptr;
    }
    out.insert(std::move(s));
  }
  Py_DECREF(it);
  if (PyErr_Occurred()) return nullptr;
  core->set_latest_only(std::move(out));
  Py_RETURN_NONE;
}

PyObject* quiet_set_finger_watch(PyObject* self_obj, PyObject* args) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  PyObject* channel;
  FingerWatch w;
  long long lo = 0, hi = 0;
  if (!PyArg_ParseTuple(args, "OddddLLdd", &channel, &w.width_lo_m, &w.width_hi_m, &w.force_lo_n, &w.force_hi_n, &lo,
                        &hi, &w.target_um, &w.apart_um))
    return nullptr;
  std::string ch;
  if (!utf8_of(channel, ch, "channel")) return nullptr;
  w.position_lo_um = lo;
  w.position_hi_um = hi;
  core->set_finger_watch(ch, w);
  Py_RETURN_NONE;
}

PyObject* quiet_clear_watches(PyObject* self_obj, PyObject*) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  core->clear_watches();
  Py_RETURN_NONE;
}

PyObject* handed_list(std::vector<Handed>& handed) {
  PyObject* out = PyList_New(0);
  if (!out) return nullptr;
  for (auto& h : handed) {
    PyObject* item = Py_BuildValue("(is#y#)", static_cast<int>(h.kind), h.channel.data(), Py_ssize_t(h.channel.size()),
                                   reinterpret_cast<const char*>(h.payload.data()), Py_ssize_t(h.payload.size()));
    if (!item || PyList_Append(out, item) < 0) {
      Py_XDECREF(item);
      Py_DECREF(out);
      return nullptr;
    }
    Py_DECREF(item);
  }
  return out;
}

PyObject* quiet_wait(PyObject* self_obj, PyObject* args) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  double timeout_s;
  PyObject *master, *last_ack, *running;
  long long last_acked, last_sim_time;
  long long through_frame = INT64_MAX, before_ns = INT64_MAX;
  if (!PyArg_ParseTuple(args, "dOLLSS|LL", &timeout_s, &master, &last_acked, &last_sim_time, &last_ack, &running,
                        &through_frame, &before_ns))
    return nullptr;
  QuietState s;
  s.last_acked = last_acked;
  s.last_sim_time = last_sim_time;
  s.quiet_through_frame = through_frame;
  s.quiet_before_ns = before_ns;
  if (!utf8_of(master, s.master, "master") || !bytes_of(last_ack, s.last_ack, "last_ack")) return nullptr;
  if (PyBytes_GET_SIZE(running) != static_cast<Py_ssize_t>(s.running.size())) {
    PyErr_SetString(PyExc_ValueError, "running: a 32-byte digest needed");
    return nullptr;
  }
  std::memcpy(s.running.data(), PyBytes_AS_STRING(running), s.running.size());
  // (a NaN, negative or huge timeout: none, or an hour; Python waits again)
  const int timeout_ms = timeout_s > 0 ? static_cast<int>(std::min(timeout_s, 3600.0) * 1000 + 0.999) : 0;
  Datagram d;
  std::vector<Handed> handed;
  bool got = false;
  int os_error = 0;
  std::string error;
  Py_BEGIN_ALLOW_THREADS
  try {
    got = core->wait(s, timeout_ms, d, handed);
  } catch (const std::system_error& e) {
    os_error = e.code().value();
    error = e.what();
  } catch (const std::exception& e) {
    error = e.what();
  }
  Py_END_ALLOW_THREADS
  if (os_error) {
    errno = os_error;
    return PyErr_SetFromErrnoWithFilename(PyExc_OSError, error.c_str());
  }
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
  PyObject* handed_out = handed_list(handed);
  if (!handed_out) {
    Py_DECREF(datagram);
    Py_DECREF(sender);
    return nullptr;
  }
  return Py_BuildValue("(NNLLLy#y#LN)", datagram, sender, static_cast<long long>(s.acked),
                       static_cast<long long>(s.last_acked), static_cast<long long>(s.last_sim_time),
                       reinterpret_cast<const char*>(s.last_ack.data()), Py_ssize_t(s.last_ack.size()),
                       reinterpret_cast<const char*>(s.running.data()), Py_ssize_t(s.running.size()),
                       static_cast<long long>(s.resends), handed_out);
}

PyObject* quiet_hold(PyObject* self_obj, PyObject* args) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  PyObject *channel, *payload;
  long long last_acked;
  if (!PyArg_ParseTuple(args, "OSL", &channel, &payload, &last_acked)) return nullptr;
  std::string ch;
  Bytes data;
  if (!utf8_of(channel, ch, "channel") || !bytes_of(payload, data, "payload")) return nullptr;
  try {
    core->hold(ch, data, last_acked);
  } catch (const std::exception& e) {
    PyErr_SetString(PyExc_RuntimeError, e.what());
    return nullptr;
  }
  Py_RETURN_NONE;
}

PyObject* quiet_release(PyObject* self_obj, PyObject*) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  std::vector<Handed> handed = core->release();
  return handed_list(handed);
}

PyObject* quiet_verdicts(PyObject* self_obj, PyObject*) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  PyObject* out = PyDict_New();
  if (!out) return nullptr;
  for (const auto& [key, count] : core->verdicts()) {
    PyObject* k = Py_BuildValue("(s#s#)", key.first.data(), Py_ssize_t(key.first.size()), key.second.data(),
                                Py_ssize_t(key.second.size()));
    PyObject* v = PyLong_FromUnsignedLongLong(count);
    const bool ok = k && v && PyDict_SetItem(out, k, v) == 0;
    Py_XDECREF(k);
    Py_XDECREF(v);
    if (!ok) {
      Py_DECREF(out);
      return nullptr;
    }
  }
  return out;
}

PyObject* quiet_latest_stats(PyObject* self_obj, PyObject*) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  PyObject* out = PyDict_New();
  if (!out) return nullptr;
  if (!set_count(out, "stale", core->stale()) || !set_count(out, "duplicates", core->duplicates())) Py_CLEAR(out);
  return out;
}

PyObject* quiet_counts(PyObject* self_obj, PyObject*) {
  QuietFrames* core = core_of(self_obj);
  if (!core) return nullptr;
  PyObject* out = PyDict_New();
  if (!out) return nullptr;
  bool ok = set_count(out, "ok", core->accepted());
  for (const auto& [reason, count] : core->rejected()) ok = ok && set_count(out, reason.c_str(), count);
  if (!ok) Py_CLEAR(out);
  return out;
}

PyObject* quiet_lost_sends(PyObject* self_obj, PyObject*) {
  QuietFrames* core = core_of(self_obj);
  return core ? PyLong_FromUnsignedLongLong(core->lost_sends()) : nullptr;
}

PyMethodDef quiet_methods[] = {
    {"set_subscribed", quiet_set_subscribed, METH_O, "The channels whose announced messages give a frame work."},
    {"set_latest_only", quiet_set_latest_only, METH_O, "Subscribed channels whose handler keeps only the newest."},
    {"set_finger_watch", quiet_set_finger_watch, METH_VARARGS,
     "A latest-only sim_state_t channel whose newest message must keep the fingers within bounds."},
    {"clear_watches", quiet_clear_watches, METH_NOARGS, "No watches (set again before each wait)."},
    {"wait", quiet_wait, METH_VARARGS, "Acks quiet frames until a datagram for Python comes or the timeout."},
    {"hold", quiet_hold, METH_VARARGS, "A verified latest-only message Python held, for the core's frames."},
    {"release", quiet_release, METH_NOARGS, "Everything the core holds, back to Python."},
    {"verdicts", quiet_verdicts, METH_NOARGS, "Messages verified and dropped, by (reason, channel)."},
    {"latest_stats", quiet_latest_stats, METH_NOARGS, "Latest-only messages dropped as stale or duplicate."},
    {"counts", quiet_counts, METH_NOARGS, "Clocks verified ('ok') and dropped, by reason (cumulative)."},
    {"lost_sends", quiet_lost_sends, METH_NOARGS, "Acks the network refused to send."},
    {nullptr, nullptr, 0, nullptr}};

PyTypeObject quiet_type = {PyVarObject_HEAD_INIT(nullptr, 0)};

}  // namespace

bool add_quiet_frames(PyObject* module) {
  quiet_type.tp_name = "skillbus_native.QuietFrames";
  quiet_type.tp_basicsize = sizeof(PyQuietFrames);
  quiet_type.tp_flags = Py_TPFLAGS_DEFAULT;
  quiet_type.tp_doc = "Acks a Python lockstep participant's quiet frames without the interpreter.";
  quiet_type.tp_new = PyType_GenericNew;
  quiet_type.tp_init = quiet_init;
  quiet_type.tp_dealloc = quiet_dealloc;
  quiet_type.tp_methods = quiet_methods;
  return add_type(module, quiet_type, "QuietFrames");
}

}  // namespace skillbus::native
