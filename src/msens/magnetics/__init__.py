"""From the field model to the coil's voltage: the one transducer core every workflow calls.

- :mod:`.potentials` — the factorised tangent operator at the bias point, source potentials,
  coil flux linkage by mesh quadrature and by summed-area table.
- :mod:`.villari` — the Villari source of each bead (bead stress × magnetoelastic law).
- :mod:`.approach` — the contact-approach source of each contact (morphed-mesh residual).
- :mod:`.magnetoelastic`, :mod:`.steel_law` — the JAS magnetoelastic law and its fit to the
  field model's B–H table.
- :mod:`.mechanisms` — incremental potentials of both mechanisms' sources, coil linkage.
- :mod:`.transducer` — per-coil sensitivities of both mechanisms, the magnets' pull on the
  beads, coil R and L; :mod:`.transducer_cache` — their on-disk cache.
- :mod:`.emf` — the EMF from the chain's contact states.
- :mod:`.mss` — the read-out circuit of a coil and the physics MsS record of one chain run.
"""
