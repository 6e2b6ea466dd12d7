#include "ntcip/snmp_manager.hpp"
#include "ntcip/snmp_logging.hpp"

#include <net-snmp/net-snmp-config.h>
#include <net-snmp/net-snmp-includes.h>
#include <fcntl.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>

namespace corridor::ntcip {

struct SnmpManager::Session {
  SnmpTarget target;
  void* handle = nullptr;  // Net-SNMP single-session handle; null when it could not open
  std::string open_error;
};

namespace {

constexpr const char* kAppType = "corridor-snmp-manager";

struct Pending {
  SnmpManager::Callback done;
  std::string note;  // what went wrong on the way, for the final answer
};

SnmpReply reply_of(netsnmp_pdu* resp) {
  SnmpReply r;
  if (resp->errstat != SNMP_ERR_NOERROR) {
    r.outcome = SnmpReply::Outcome::error_status;
    r.error_status = resp->errstat;
    r.error_index = resp->errindex;
    r.message = snmp_errstring(static_cast<int>(resp->errstat));
    return r;
  }
  r.outcome = SnmpReply::Outcome::ok;
  for (netsnmp_variable_list* vb = resp->variables; vb != nullptr; vb = vb->next_variable) {
    Oid name(vb->name, vb->name + vb->name_length);
    std::optional<std::int64_t> value;
    if ((vb->type == ASN_INTEGER || vb->type == ASN_TIMETICKS || vb->type == ASN_GAUGE || vb->type == ASN_COUNTER) &&
        vb->val.integer != nullptr) {
      value = *vb->val.integer;
    }
    r.values.emplace_back(std::move(name), value);
  }
  return r;
}

int on_reply(int op, netsnmp_session*, int, netsnmp_pdu* resp, void* magic) {
  auto* pending = static_cast<Pending*>(magic);
  // Only an answer and a timeout end a request: a failed send (a controller whose port answers
  // with an ICMP "unreachable") is retried by the library and comes back here as a timeout.
  if (op == NETSNMP_CALLBACK_OP_SEND_FAILED || op == NETSNMP_CALLBACK_OP_SEC_ERROR) {
    pending->note = op == NETSNMP_CALLBACK_OP_SEND_FAILED ? "sending failed (the controller's port refuses)" : "a security error";
    return 1;
  }
  if (op != NETSNMP_CALLBACK_OP_RECEIVED_MESSAGE && op != NETSNMP_CALLBACK_OP_TIMED_OUT) return 1;
  SnmpReply r;
  if (op == NETSNMP_CALLBACK_OP_RECEIVED_MESSAGE && resp != nullptr) {
    r = reply_of(resp);
  } else {
    r.outcome = SnmpReply::Outcome::timeout;
    r.message = pending->note.empty() ? "no answer" : "no answer: " + pending->note;
  }
  if (pending->done) pending->done(r);
  delete pending;
  return 1;
}

void* open_session(const SnmpTarget& t, std::string& error) {
  netsnmp_session s;
  snmp_sess_init(&s);
  const std::string peer = "udp:" + t.host + ":" + std::to_string(t.port);
  s.peername = const_cast<char*>(peer.c_str());
  s.timeout = static_cast<long>(t.timeout_s * 1e6);
  s.retries = t.retries;
  const SnmpCredentials& c = t.credentials;
  std::string community = c.write_community;  // a manager that sets: the community that may
  if (c.version != SnmpVersion::v3) {
    s.version = c.version == SnmpVersion::v1 ? SNMP_VERSION_1 : SNMP_VERSION_2c;
    s.community = reinterpret_cast<u_char*>(community.data());
    s.community_len = community.size();
  } else {
    s.version = SNMP_VERSION_3;
    s.securityModel = SNMP_SEC_MODEL_USM;
    s.securityName = const_cast<char*>(c.user.c_str());
    s.securityNameLen = c.user.size();
    s.securityLevel = c.level == SecurityLevel::auth_priv      ? SNMP_SEC_LEVEL_AUTHPRIV
                      : c.level == SecurityLevel::auth_no_priv ? SNMP_SEC_LEVEL_AUTHNOPRIV
                                                               : SNMP_SEC_LEVEL_NOAUTH;
    if (c.level != SecurityLevel::no_auth_no_priv) {
      if (c.auth_protocol == "MD5") {
        s.securityAuthProto = usmHMACMD5AuthProtocol;
        s.securityAuthProtoLen = USM_AUTH_PROTO_MD5_LEN;
      } else if (c.auth_protocol == "SHA-256") {
        s.securityAuthProto = usmHMAC192SHA256AuthProtocol;
        s.securityAuthProtoLen = sizeof(usmHMAC192SHA256AuthProtocol) / sizeof(::oid);
      } else {
        s.securityAuthProto = usmHMACSHA1AuthProtocol;
        s.securityAuthProtoLen = USM_AUTH_PROTO_SHA_LEN;
      }
      s.securityAuthKeyLen = USM_AUTH_KU_LEN;
      if (generate_Ku(s.securityAuthProto, static_cast<u_int>(s.securityAuthProtoLen),
                      reinterpret_cast<const u_char*>(c.auth_password.data()), c.auth_password.size(), s.securityAuthKey,
                      &s.securityAuthKeyLen) != SNMPERR_SUCCESS) {
        error = "cannot derive the authentication key";
        return nullptr;
      }
    }
    if (c.level == SecurityLevel::auth_priv) {
      if (c.priv_protocol == "DES") {
        s.securityPrivProto = usmDESPrivProtocol;
        s.securityPrivProtoLen = USM_PRIV_PROTO_DES_LEN;
      } else {
        s.securityPrivProto = usmAESPrivProtocol;
        s.securityPrivProtoLen = USM_PRIV_PROTO_AES_LEN;
      }
      s.securityPrivKeyLen = USM_PRIV_KU_LEN;
      // The privacy key is derived with the authentication hash (RFC 3414).
      if (generate_Ku(s.securityAuthProto, static_cast<u_int>(s.securityAuthProtoLen),
                      reinterpret_cast<const u_char*>(c.priv_password.data()), c.priv_password.size(), s.securityPrivKey,
                      &s.securityPrivKeyLen) != SNMPERR_SUCCESS) {
        error = "cannot derive the privacy key";
        return nullptr;
      }
    }
  }
  void* handle = snmp_sess_open(&s);
  if (handle == nullptr) {
    int sys_errno = 0, snmp_errno = 0;
    char* text = nullptr;
    snmp_error(&s, &sys_errno, &snmp_errno, &text);
    error = text != nullptr ? text : "cannot open the session";
    free(text);
  }
  return handle;
}

}  // namespace

SnmpManager::SnmpManager() {
  if (pipe2(wake_, O_CLOEXEC | O_NONBLOCK) != 0) throw std::runtime_error("cannot create the SNMP manager's wake-up pipe");
  route_snmp_logs_to_spdlog();
  // Nothing read from /etc/snmp or the home directory, nothing written to /var/lib/snmp.
  netsnmp_ds_set_boolean(NETSNMP_DS_LIBRARY_ID, NETSNMP_DS_LIB_DONT_READ_CONFIGS, 1);
  netsnmp_ds_set_boolean(NETSNMP_DS_LIBRARY_ID, NETSNMP_DS_LIB_DONT_PERSIST_STATE, 1);
  const auto state = std::filesystem::temp_directory_path() / "corridor-snmp-manager";
  std::error_code ec;
  std::filesystem::create_directories(state, ec);
  netsnmp_ds_set_string(NETSNMP_DS_LIBRARY_ID, NETSNMP_DS_LIB_PERSISTENT_DIR, state.c_str());
  setenv("MIBS", "", 1);
  init_snmp(kAppType);
  thread_ = std::thread([this] { run(); });
}

SnmpManager::~SnmpManager() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  const char c = 1;
  (void)!write(wake_[1], &c, 1);
  thread_.join();
  for (auto& s : sessions_) {
    if (s->handle != nullptr) snmp_sess_close(s->handle);
  }
  snmp_shutdown(kAppType);
  close(wake_[0]);
  close(wake_[1]);
}

void SnmpManager::post(std::function<void()> task) {
  {
    std::lock_guard lock(mutex_);
    tasks_.push_back(std::move(task));
  }
  const char c = 1;
  (void)!write(wake_[1], &c, 1);
}

SnmpManager::SessionId SnmpManager::open(const SnmpTarget& target) {
  SessionId id = 0;
  {
    std::lock_guard lock(mutex_);
    id = opened_++;
  }
  post([this, id, target] {
    auto s = std::make_unique<Session>();
    s->target = target;
    s->handle = open_session(target, s->open_error);
    if (s->handle == nullptr) spdlog::warn("event=snmp_open_failed peer={}:{} error=\"{}\"", target.host, target.port, s->open_error);
    if (sessions_.size() <= id) sessions_.resize(id + 1);
    sessions_[id] = std::move(s);
  });
  return id;
}

void SnmpManager::get(SessionId session, std::vector<Oid> oids, Callback done) {
  post([this, session, oids = std::move(oids), done = std::move(done)]() mutable {
    Session* s = session < sessions_.size() ? sessions_[session].get() : nullptr;
    if (s == nullptr || s->handle == nullptr) {
      done({SnmpReply::Outcome::failure, 0, 0, s == nullptr ? "no such session" : s->open_error, {}});
      return;
    }
    netsnmp_pdu* pdu = snmp_pdu_create(SNMP_MSG_GET);
    for (const Oid& o : oids) {
      std::vector<::oid> ids(o.begin(), o.end());
      snmp_add_null_var(pdu, ids.data(), ids.size());
    }
    auto* pending = new Pending{std::move(done), {}};
    if (snmp_sess_async_send(s->handle, pdu, on_reply, pending) == 0) {
      snmp_free_pdu(pdu);
      pending->done({SnmpReply::Outcome::failure, 0, 0, snmp_api_errstring(snmp_sess_session(s->handle)->s_snmp_errno), {}});
      delete pending;
    }
  });
}

void SnmpManager::set(SessionId session, std::vector<std::pair<Oid, std::int64_t>> values, Callback done) {
  post([this, session, values = std::move(values), done = std::move(done)]() mutable {
    Session* s = session < sessions_.size() ? sessions_[session].get() : nullptr;
    if (s == nullptr || s->handle == nullptr) {
      done({SnmpReply::Outcome::failure, 0, 0, s == nullptr ? "no such session" : s->open_error, {}});
      return;
    }
    netsnmp_pdu* pdu = snmp_pdu_create(SNMP_MSG_SET);
    for (const auto& [o, v] : values) {
      std::vector<::oid> ids(o.begin(), o.end());
      const long value = static_cast<long>(v);
      snmp_pdu_add_variable(pdu, ids.data(), ids.size(), ASN_INTEGER, &value, sizeof value);
    }
    auto* pending = new Pending{std::move(done), {}};
    if (snmp_sess_async_send(s->handle, pdu, on_reply, pending) == 0) {
      snmp_free_pdu(pdu);
      pending->done({SnmpReply::Outcome::failure, 0, 0, snmp_api_errstring(snmp_sess_session(s->handle)->s_snmp_errno), {}});
      delete pending;
    }
  });
}

void SnmpManager::run() {
  for (;;) {
    std::deque<std::function<void()>> tasks;
    {
      std::lock_guard lock(mutex_);
      if (stop_) return;
      tasks.swap(tasks_);
    }
    for (auto& t : tasks) t();
    std::vector<pollfd> fds{{wake_[0], POLLIN, 0}};
    std::vector<Session*> polled;
    int timeout_ms = 1000;
    for (auto& s : sessions_) {
      if (s == nullptr || s->handle == nullptr) continue;
      netsnmp_transport* t = snmp_sess_transport(s->handle);
      if (t == nullptr || t->sock < 0) continue;
      fds.push_back({t->sock, POLLIN, 0});
      polled.push_back(s.get());
      // The next retransmission or timeout the library has due.
      int nfds = 0, block = 1;
      fd_set unused;
      FD_ZERO(&unused);
      timeval tv{};
      snmp_sess_select_info(s->handle, &nfds, &unused, &tv, &block);
      if (block == 0) timeout_ms = std::min<int>(timeout_ms, static_cast<int>(tv.tv_sec * 1000 + tv.tv_usec / 1000));
    }
    const int n = ::poll(fds.data(), fds.size(), std::max(0, timeout_ms));
    if (n > 0 && (fds[0].revents & POLLIN) != 0) {
      char buf[64];
      while (read(wake_[0], buf, sizeof buf) > 0) {
      }
    }
    for (std::size_t i = 0; i < polled.size(); ++i) {
      if (n > 0 && (fds[i + 1].revents & POLLIN) != 0) {
        fd_set set;
        FD_ZERO(&set);
        FD_SET(fds[i + 1].fd, &set);
        snmp_sess_read(polled[i]->handle, &set);
      }
      snmp_sess_timeout(polled[i]->handle);  // retransmits, or answers a timeout
    }
  }
}

}  // namespace corridor::ntcip
