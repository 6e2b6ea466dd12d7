#include "ntcip/snmp_agent.hpp"
#include "ntcip/snmp_logging.hpp"

#include <net-snmp/net-snmp-config.h>
#include <net-snmp/net-snmp-includes.h>
#include <poll.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>

namespace corridor::ntcip {

struct SnmpAgent::Endpoint {
  SnmpAgent* agent = nullptr;
  VirtualIntersection* intersection = nullptr;
  void* session = nullptr;  // Net-SNMP's single-session handle
  std::string label;
  double now_s = 0.0;
  std::size_t answered = 0;
};

namespace {

constexpr const char* kAppType = "corridor-signal-agent";
constexpr std::size_t kMaxBulkVarbinds = 200;

Oid oid_of(const netsnmp_variable_list* vb) { return Oid(vb->name, vb->name + vb->name_length); }

// RFC 2576 section 4.3: a v2 error as SNMPv1 knows it.
long v1_error(long err) {
  switch (err) {
    case SNMP_ERR_NOERROR:
    case SNMP_ERR_TOOBIG:
    case SNMP_ERR_NOSUCHNAME:
    case SNMP_ERR_BADVALUE:
    case SNMP_ERR_READONLY:
    case SNMP_ERR_GENERR: return err;
    case SNMP_ERR_WRONGVALUE:
    case SNMP_ERR_WRONGENCODING:
    case SNMP_ERR_WRONGTYPE:
    case SNMP_ERR_WRONGLENGTH:
    case SNMP_ERR_INCONSISTENTVALUE: return SNMP_ERR_BADVALUE;
    default: return SNMP_ERR_NOSUCHNAME;
  }
}

void put_value(netsnmp_variable_list* vb, const Value& v) {
  switch (v.type) {
    case Value::Type::integer: snmp_set_var_typed_integer(vb, ASN_INTEGER, static_cast<long>(v.integer)); break;
    case Value::Type::timeticks: snmp_set_var_typed_integer(vb, ASN_TIMETICKS, static_cast<long>(v.integer)); break;
    case Value::Type::octets:
      snmp_set_var_typed_value(vb, ASN_OCTET_STR, reinterpret_cast<const u_char*>(v.octets.data()), v.octets.size());
      break;
    case Value::Type::object_id: {
      std::vector<::oid> ids(v.object_id.begin(), v.object_id.end());
      snmp_set_var_typed_value(vb, ASN_OBJECT_ID, reinterpret_cast<const u_char*>(ids.data()), ids.size() * sizeof(::oid));
      break;
    }
  }
}

// Whether an OID falls under a table this controller has (for noSuchInstance against noSuchObject).
bool under_known_table(const Oid& o) { return o.size() > oid::kAsc.size() && std::equal(oid::kAsc.begin(), oid::kAsc.end(), o.begin()); }

netsnmp_pdu* respond(SnmpAgent::Endpoint& ep, netsnmp_pdu* req) {
  VirtualIntersection& x = *ep.intersection;
  const bool v1 = req->version == SNMP_VERSION_1;
  netsnmp_pdu* resp = snmp_clone_pdu(req);  // keeps the request id, the reply address and v3's security state
  if (resp == nullptr) return nullptr;
  resp->command = SNMP_MSG_RESPONSE;
  resp->errstat = SNMP_ERR_NOERROR;
  resp->errindex = 0;
  const auto fail = [&](long err, long index) {
    // On an error the response carries the request's varbinds unchanged.
    snmp_free_varbind(resp->variables);
    resp->variables = snmp_clone_varbind(req->variables);
    resp->errstat = v1 ? v1_error(err) : err;
    resp->errindex = index;
  };
  x.step(ep.now_s);
  switch (req->command) {
    case SNMP_MSG_GET:
    case SNMP_MSG_GETNEXT: {
      long i = 1;
      for (netsnmp_variable_list* vb = resp->variables; vb != nullptr; vb = vb->next_variable, ++i) {
        Oid name = oid_of(vb);
        if (req->command == SNMP_MSG_GETNEXT) {
          const std::optional<Oid> next = x.next(name);
          if (!next) {
            if (v1) {
              fail(SNMP_ERR_NOSUCHNAME, i);
              break;
            }
            snmp_set_var_typed_value(vb, SNMP_ENDOFMIBVIEW, nullptr, 0);
            continue;
          }
          name = *next;
          std::vector<::oid> ids(name.begin(), name.end());
          snmp_set_var_objid(vb, ids.data(), ids.size());
        }
        const std::optional<Value> v = x.get(name, ep.now_s);
        if (v) {
          put_value(vb, *v);
        } else if (v1) {
          fail(SNMP_ERR_NOSUCHNAME, i);
          break;
        } else {
          snmp_set_var_typed_value(vb, under_known_table(name) ? SNMP_NOSUCHINSTANCE : SNMP_NOSUCHOBJECT, nullptr, 0);
        }
      }
      break;
    }
    case SNMP_MSG_GETBULK: {
      const long non_repeaters = std::max(0L, req->non_repeaters);
      const long max_repetitions = std::max(0L, req->max_repetitions);
      snmp_free_varbind(resp->variables);
      resp->variables = nullptr;
      std::vector<Oid> asked;
      for (netsnmp_variable_list* vb = req->variables; vb != nullptr; vb = vb->next_variable) asked.push_back(oid_of(vb));
      std::size_t total = 0;
      const auto add_next = [&](Oid& cursor) {
        const std::optional<Oid> next = x.next(cursor);
        std::vector<::oid> ids(next ? next->begin() : cursor.begin(), next ? next->end() : cursor.end());
        netsnmp_variable_list* vb = snmp_pdu_add_variable(resp, ids.data(), ids.size(), ASN_NULL, nullptr, 0);
        ++total;
        if (!next) {
          snmp_set_var_typed_value(vb, SNMP_ENDOFMIBVIEW, nullptr, 0);
          return false;
        }
        cursor = *next;
        put_value(vb, *x.get(cursor, ep.now_s));
        return true;
      };
      const auto non_rep = static_cast<std::size_t>(std::min<long>(non_repeaters, static_cast<long>(asked.size())));
      for (std::size_t i = 0; i < non_rep; ++i) add_next(asked[i]);
      std::vector<Oid> cursors(asked.begin() + static_cast<std::ptrdiff_t>(non_rep), asked.end());
      for (long r = 0; r < max_repetitions && !cursors.empty(); ++r) {
        if (total + cursors.size() > kMaxBulkVarbinds) break;  // whole rows only
        bool any = false;
        for (Oid& c : cursors) any = add_next(c) || any;
        if (!any) break;
      }
      break;
    }
    case SNMP_MSG_SET: {
      // Every object checked before any is set: a SET is taken whole or not at all.
      std::vector<std::pair<Oid, Value>> writes;
      long i = 1;
      for (netsnmp_variable_list* vb = req->variables; vb != nullptr; vb = vb->next_variable, ++i) {
        Value v;
        if (vb->type == ASN_INTEGER && vb->val.integer != nullptr) {
          v.integer = *vb->val.integer;
        } else {
          v.type = Value::Type::octets;  // anything but an INTEGER is the wrong type here
        }
        const SetStatus status = x.check_set(oid_of(vb), v);
        if (status != SetStatus::ok) {
          const long err = status == SetStatus::no_such_object ? (under_known_table(oid_of(vb)) ? SNMP_ERR_NOCREATION : SNMP_ERR_NOTWRITABLE)
                           : status == SetStatus::not_writable ? SNMP_ERR_NOTWRITABLE
                           : status == SetStatus::wrong_type   ? SNMP_ERR_WRONGTYPE
                                                               : SNMP_ERR_WRONGVALUE;
          fail(err, i);
          return resp;
        }
        writes.emplace_back(oid_of(vb), v);
      }
      for (const auto& [o, v] : writes) x.set(o, v, ep.now_s);
      break;  // the response repeats the request's varbinds
    }
    default:
      snmp_free_pdu(resp);
      return nullptr;
  }
  return resp;
}

// 1: answer; 0: drop silently (an unknown community); -1: v3 authorizationError; -2: noAccess.
int access(const SnmpAgent::Endpoint& ep, const AgentSecurity& sec, const netsnmp_pdu* pdu) {
  if (pdu->version == SNMP_VERSION_1 || pdu->version == SNMP_VERSION_2c) {
    const std::string community(reinterpret_cast<const char*>(pdu->community), pdu->community_len);
    if (community == sec.write_community) return 1;
    if (community == sec.read_community) return pdu->command == SNMP_MSG_SET ? -2 : 1;
    snmp_increment_statistic(STAT_SNMPINBADCOMMUNITYNAMES);
    spdlog::debug("event=snmp_bad_community agent={}", ep.label);
    return 0;
  }
  if (pdu->version == SNMP_VERSION_3 && sec.v3_user) {
    // USM has verified the digest and decrypted; the level is ours to require.
    const std::string user(pdu->securityName != nullptr ? pdu->securityName : "", pdu->securityNameLen);
    if (pdu->securityModel == SNMP_SEC_MODEL_USM && pdu->securityLevel == SNMP_SEC_LEVEL_AUTHPRIV && user == sec.v3_user->name &&
        pdu->contextNameLen == 0) {
      return 1;
    }
    return -1;
  }
  return pdu->version == SNMP_VERSION_3 ? -1 : 0;
}

const AgentSecurity* g_security_for_callback = nullptr;  // set while one SnmpAgent exists (one per process)

int on_message(int op, netsnmp_session* session, int /*reqid*/, netsnmp_pdu* pdu, void* magic) {
  if (op != NETSNMP_CALLBACK_OP_RECEIVED_MESSAGE) return 1;
  auto& ep = *static_cast<SnmpAgent::Endpoint*>(magic);
  // A v3 message whose digest failed reaches the callback too (USM has already sent its report).
  if (session->s_snmp_errno == SNMPERR_USM_AUTHENTICATIONFAILURE) return 1;
  switch (pdu->command) {
    case SNMP_MSG_GET:
    case SNMP_MSG_GETNEXT:
    case SNMP_MSG_GETBULK:
    case SNMP_MSG_SET: break;
    default: return 1;
  }
  if (pdu->version == SNMP_VERSION_1 && pdu->command == SNMP_MSG_GETBULK) return 1;  // RFC 3584: discarded
  const int allowed = access(ep, *g_security_for_callback, pdu);
  if (allowed == 0) return 1;
  netsnmp_pdu* resp = nullptr;
  if (allowed < 0) {
    resp = snmp_clone_pdu(pdu);
    resp->command = SNMP_MSG_RESPONSE;
    resp->errstat = allowed == -1 ? SNMP_ERR_AUTHORIZATIONERROR : (pdu->version == SNMP_VERSION_1 ? SNMP_ERR_NOSUCHNAME : SNMP_ERR_NOACCESS);
    resp->errindex = allowed == -1 ? 0 : 1;
  } else {
    resp = respond(ep, pdu);
  }
  if (resp == nullptr) return 1;
  if (snmp_sess_send(ep.session, resp) == 0) {  // 0: not sent, and not freed
    const int err = snmp_sess_session(ep.session)->s_snmp_errno;
    snmp_free_pdu(resp);
    if (err == SNMPERR_TOO_LONG) {
      resp = snmp_clone_pdu(pdu);
      snmp_free_varbind(resp->variables);
      resp->variables = nullptr;
      resp->command = SNMP_MSG_RESPONSE;
      resp->errstat = SNMP_ERR_TOOBIG;
      resp->errindex = 0;
      if (snmp_sess_send(ep.session, resp) == 0) snmp_free_pdu(resp);
    } else {
      spdlog::warn("event=snmp_send_failed agent={} error=\"{}\"", ep.label, snmp_api_errstring(err));
    }
  }
  ++ep.answered;
  return 1;
}

}  // namespace

SnmpAgent::SnmpAgent(AgentSecurity security) : security_(std::move(security)) {
  if (g_security_for_callback != nullptr) throw SnmpError("one SNMP agent per process: Net-SNMP keeps one engine");
  if (security_.v3_user && (security_.v3_user->auth_password.size() < 8 || security_.v3_user->priv_password.size() < 8)) {
    throw SnmpError("SNMPv3 passwords must be at least 8 characters (RFC 3414)");
  }
  std::error_code ec;
  if (security_.state_dir.empty()) security_.state_dir = std::filesystem::temp_directory_path() / "corridor-signal-agent";
  std::filesystem::create_directories(security_.state_dir, ec);
  if (ec) throw SnmpError("cannot create the SNMP state directory " + security_.state_dir.string() + ": " + ec.message());
  route_snmp_logs_to_spdlog();
  // Only our own state is read: no snmp.conf from /etc or the home directory.
  netsnmp_ds_set_string(NETSNMP_DS_LIBRARY_ID, NETSNMP_DS_LIB_CONFIGURATION_DIR, security_.state_dir.c_str());
  netsnmp_ds_set_string(NETSNMP_DS_LIBRARY_ID, NETSNMP_DS_LIB_PERSISTENT_DIR, security_.state_dir.c_str());
  netsnmp_ds_set_boolean(NETSNMP_DS_LIBRARY_ID, NETSNMP_DS_LIB_NO_TOKEN_WARNINGS, 1);
  netsnmp_ds_set_int(NETSNMP_DS_LIBRARY_ID, NETSNMP_DS_LIB_MIB_WARNINGS, 0);
  setenv("MIBS", "", 1);  // no MIB files: the objects are ours
  // RFC 3411 engine ID: enterprise 1206 (NTCIP), format 4 (text).
  std::vector<u_char> engine{0x80, 0x00, 0x04, 0xB6, 0x04};
  const std::string name = security_.engine_name.substr(0, 27);
  engine.insert(engine.end(), name.begin(), name.end());
  set_exact_engineID(engine.data(), engine.size());
  init_snmp(kAppType);
  snmp_store(kAppType);  // the incremented boot counter, at once, so that a crash keeps it
  if (security_.v3_user) {
    std::string line = security_.v3_user->name + " SHA " + security_.v3_user->auth_password + " AES " +
                       security_.v3_user->priv_password;
    usm_parse_create_usmUser("createUser", line.data());
  }
  g_security_for_callback = &security_;
}

SnmpAgent::~SnmpAgent() {
  for (auto& ep : endpoints_) {
    if (ep->session != nullptr) snmp_sess_close(ep->session);
  }
  snmp_shutdown(kAppType);
  g_security_for_callback = nullptr;
}

void SnmpAgent::serve(const std::string& host, unsigned short port, VirtualIntersection& intersection) {
  auto ep = std::make_unique<Endpoint>();
  ep->agent = this;
  ep->intersection = &intersection;
  ep->label = host + ":" + std::to_string(port);
  const std::string spec = "udp:" + ep->label;
  netsnmp_transport* t = netsnmp_transport_open_server("snmp", spec.c_str());
  if (t == nullptr) throw SnmpError("cannot listen on UDP " + ep->label + " (in use, or not an address of this host)");
  netsnmp_session s;
  snmp_sess_init(&s);
  s.version = SNMP_DEFAULT_VERSION;  // v1, v2c and v3 on one port
  s.isAuthoritative = SNMP_SESS_AUTHORITATIVE;
  s.callback = on_message;
  s.callback_magic = ep.get();
  ep->session = snmp_sess_add(&s, t, nullptr, nullptr);  // owns t from here
  if (ep->session == nullptr) throw SnmpError("cannot open an SNMP session on " + ep->label);
  endpoints_.push_back(std::move(ep));
}

void SnmpAgent::poll(int timeout_ms, double now_s) {
  std::vector<pollfd> fds;
  for (const auto& ep : endpoints_) fds.push_back({snmp_sess_transport(ep->session)->sock, POLLIN, 0});
  const int n = ::poll(fds.data(), fds.size(), timeout_ms);
  if (n <= 0) return;
  for (std::size_t i = 0; i < fds.size(); ++i) {
    if ((fds[i].revents & POLLIN) == 0) continue;
    endpoints_[i]->now_s = now_s;
    fd_set set;
    FD_ZERO(&set);
    FD_SET(fds[i].fd, &set);
    snmp_sess_read(endpoints_[i]->session, &set);
  }
  run_alarms();
}

std::size_t SnmpAgent::requests_answered() const {
  std::size_t n = 0;
  for (const auto& ep : endpoints_) n += ep->answered;
  return n;
}

}  // namespace corridor::ntcip
