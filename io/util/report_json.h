#pragma once
/// \file report_json.h
/// Reports as JSON (the `--json` output of the command-line tool and the .json report files).

#include "io/util/json.h"
#include "metrics/compare_report.h"

namespace normalflow {

/// compare.json and `normalflow compare --json`: {"command":"compare","reference":...,
/// "reference_stats":{...} (when there is a candidate),"protocol":{...},"candidates":[{...},...]}.
/// "self_intersecting_pairs" is present only when measured, a candidate's "correspondence":{...}
/// (CorrespondenceErrors) and the protocol's "correspondence":true only with CompareOptions::correspondence.
/// Keys in a fixed order.
Json to_json(const CompareReport& r);

}  // namespace normalflow
