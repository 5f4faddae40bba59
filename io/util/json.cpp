#include "io/util/json.h"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace normalflow {

Json& Json::set(std::string key, Json value) { return (*this)[key] = std::move(value), *this; }

Json& Json::push(Json value) {
    members_.emplace_back(std::string(), std::move(value));
    return *this;
}

Json& Json::operator[](const std::string& key) {
    for (auto& [k, v] : members_)
        if (k == key) return v;
    members_.emplace_back(key, Json());
    return members_.back().second;
}

std::string Json::dump() const {
    std::string out;
    dump_to(out);
    return out;
}

namespace {
void escape(std::string& out, const std::string& s) {
    out += '"';
    for (unsigned char c : s) {
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\n': out += "\\n"; break;
            case '\r': out += "\\r"; break;
            case '\t': out += "\\t"; break;
            default:
                if (c < 0x20) {
                    char buf[8];
                    std::snprintf(buf, sizeof buf, "\\u%04x", c);
                    out += buf;
                } else {
                    out += char(c);
                }
        }
    }
    out += '"';
}
}  // namespace

void Json::dump_to(std::string& out) const {
    switch (kind_) {
        case Kind::Null: out += "null"; break;
        case Kind::Bool: out += b_ ? "true" : "false"; break;
        case Kind::Integer: out += std::to_string(i_); break;
        case Kind::Number: {
            if (!std::isfinite(d_)) {
                out += "null";
                break;
            }
            char buf[32];
            auto r = std::to_chars(buf, buf + sizeof buf, d_);
            out.append(buf, r.ptr);
            break;
        }
        case Kind::String: escape(out, s_); break;
        case Kind::Array: {
            out += '[';
            for (std::size_t i = 0; i < members_.size(); ++i) {
                if (i) out += ',';
                members_[i].second.dump_to(out);
            }
            out += ']';
            break;
        }
        case Kind::Object: {
            out += '{';
            for (std::size_t i = 0; i < members_.size(); ++i) {
                if (i) out += ',';
                escape(out, members_[i].first);
                out += ':';
                members_[i].second.dump_to(out);
            }
            out += '}';
            break;
        }
    }
}

}  // namespace normalflow
