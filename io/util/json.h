#pragma once
/// \file json.h
/// A minimal JSON writer for reports (`--json`, benchmark tables): objects, arrays, numbers, strings,
/// booleans. Keys keep their insertion order. Non-finite numbers are written as null.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace normalflow {

class Json {
public:
    Json() : kind_(Kind::Null) {}
    Json(bool b) : kind_(Kind::Bool), b_(b) {}
    Json(double d) : kind_(Kind::Number), d_(d) {}
    Json(float d) : kind_(Kind::Number), d_(d) {}
    Json(int i) : kind_(Kind::Integer), i_(i) {}
    Json(long i) : kind_(Kind::Integer), i_(i) {}
    Json(long long i) : kind_(Kind::Integer), i_(i) {}
    Json(unsigned i) : kind_(Kind::Integer), i_(static_cast<long long>(i)) {}
    Json(unsigned long i) : kind_(Kind::Integer), i_(static_cast<long long>(i)) {}
    Json(unsigned long long i) : kind_(Kind::Integer), i_(static_cast<long long>(i)) {}
    Json(const char* s) : kind_(Kind::String), s_(s) {}
    Json(std::string s) : kind_(Kind::String), s_(std::move(s)) {}
    Json(std::string_view s) : kind_(Kind::String), s_(s) {}

    static Json object() {
        Json j;
        j.kind_ = Kind::Object;
        return j;
    }
    static Json array() {
        Json j;
        j.kind_ = Kind::Array;
        return j;
    }
    template <class T>
    static Json array(const std::vector<T>& v) {
        Json j = array();
        for (const auto& x : v) j.push(Json(x));
        return j;
    }

    /// Sets key in an object (replacing an existing key); returns *this for chaining.
    Json& set(std::string key, Json value);
    /// Appends to an array.
    Json& push(Json value);
    /// The member `key` of an object, inserted as null if absent.
    Json& operator[](const std::string& key);

    /// The string values of an array (other elements skipped), e.g. a report's warnings.
    std::vector<std::string> strings() const {
        std::vector<std::string> out;
        for (const auto& m : members_)
            if (m.second.kind_ == Kind::String) out.push_back(m.second.s_);
        return out;
    }

    /// Compact single-line serialisation.
    std::string dump() const;

private:
    enum class Kind { Null, Bool, Number, Integer, String, Array, Object };
    Kind kind_;
    bool b_ = false;
    double d_ = 0;
    long long i_ = 0;
    std::string s_;
    std::vector<std::pair<std::string, Json>> members_;  // objects (key) and arrays (empty key)
    void dump_to(std::string& out) const;
};

}  // namespace normalflow
