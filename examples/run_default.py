"""Run the default study (the paper's MsS predicted from physics) and print its Table-2 rows.

    python examples/run_default.py

The first run in a new install compiles the chain kernel once (msens.progress.KERNEL_COMPILE_S
on an idle 2-core machine, in a second process while the run prepares; kept in the user cache
folder, so reinstalling does not repeat it); after that it takes a few seconds.
"""

import msens.api as ms

study = ms.load_default()  # studies/paper-mss.toml, shipped with the package
result = ms.run(study)
print(result)  # a short summary; result.setups[0].sensors[0] holds the records

print(f"\n{'position':<8} {'particle':>8} {'TOF us':>8} {'AR':>6} {'peak N':>7} "
      f"{'exp TOF':>8} {'exp AR':>6}")
for row in result.rows():  # the rows of summary.json, as dicts
    ref = row.get("reference", {})
    print(f"{row['position']:<8} {row['particle']:>8} {row['tof_us']:>8.1f} {row['ar']:>6.3f} "
          f"{row['incident_peak_N']:>7.2f} {ref.get('experiment_tof_us', float('nan')):>8.1f} "
          f"{ref.get('experiment_ar', float('nan')):>6.2f}")
