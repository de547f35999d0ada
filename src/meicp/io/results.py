"""Everything ``meicp solve`` leaves on disk: :func:`write_results`.

In the output directory::

    results.h5      the scene, versions, contact states and forces, modes, verdict (below)
    lattice.h5      the lattice (:func:`~meicp.io.lattice_output.write_lattice`) with node
    lattice.xdmf    fields ``mode_0``, ``mode_1``... (each scaled as in the PNG), the fastest
                    flutter mode's ``flutter_0_real`` and ``flutter_0_imag`` when there is one,
                    ``contact_state`` (codes below), the node indices ``i`` and ``j``, and,
                    when the static equilibrium was solved, ``static_u`` (its displacement)
                    and the contact reactions ``r_n``, ``r_t`` (NaN off the contact nodes);
                    a damped scene's bonds carry ``bond_viscosity`` beside ``bond_stiffness``:
                    open the .xdmf in ParaView, Warp By Vector with ``mode_k`` (scale 1 = the
                    PNG's picture)
    mode.png        the fastest mode on the deformed lattice (or the "stable" lattice)
                    (each PNG is an extra: one Matplotlib cannot draw is left out with a
                    warning, the other files written all the same)
    flutter_mode.png  the fastest flutter mode (real part of its shape; only when there is one)
    contacts.png    states (and forces) along each contact line (only when there is one)

``results.h5`` layout (strings are UTF-8; ``None`` is never stored: absent means unknown):

=================================  ==========================================================
``/`` attributes                   ``format = "meicp-results"``, ``format_version``,
                                   ``meicp_version``, ``title``, ``source``, ``created``,
                                   ``status``, ``success``, ``message``, ``iterations``,
                                   ``residual``, ``analysis`` (instability | modal: a scene
                                   without contact), ``verdict`` (stable | unstable |
                                   undecided | no contact), ``stable`` (1 | 0 | -1 for
                                   undecided), ``evidence``, ``n_modes``, ``ranks``,
                                   ``units_convention``, ``divergence`` and ``flutter``
                                   (1 | 0 | -1 for undecided), ``divergence_failure`` (only
                                   when a divergence solver failed: why divergence is
                                   undecided; ``status`` is then ``inconclusive`` unless
                                   flutter decided the verdict), ``flutter_evidence``,
                                   ``n_flutter_modes``, ``flutter_growth_lower`` /
                                   ``_upper`` (NaN: no bound proved) / ``_exact`` /
                                   ``_upper_loose`` (1: Bendixson's rectangle) /
                                   ``_evidence`` (the certified bracket of the fastest
                                   flutter growth rate), ``divergence_tests`` (the test behind
                                   each MEiCP's divergence verdict: enumerate,
                                   rayleigh-inertia, rayleigh-window+condensed-…,
                                   certified-mode, none) and ``divergence_proofs`` (JSON:
                                   test, statement, sigma_window, supports visited;
                                   numbers as :mod:`meicp.core.json_values` writes them)
``/scene``                         the scene as TOML text (the file's own text when known,
                                   else regenerated from the parsed scene)
``/scene_summary``                 attributes nx, ny, n_nodes, n_dofs, spacing, shear,
                                   boundary_<side>, base_friction; ``layers/{name, rows,
                                   stiffness, density}`` (and ``viscosity`` when damped),
                                   ``interfaces/{below, kind, stiffness, friction}`` (NaN
                                   where not applicable)
``/damping`` (damped scenes only)  attribute ``mass`` (α of ``[damping] mass``); subgroups
                                   ``viscosity`` and ``interface_viscosity``, one attribute
                                   per material / bonded interface (docs/damping.md)
``/versions``                      attributes: python, numpy, scipy, petsc, slepc, mpi, ...
``/sizes``, ``/timings``           attributes copied from the result (timings in seconds)
``/contact``                       attribute ``codes`` (the per-node code legend)
``/contact/base``                  ``states`` (nx,) S, ``code`` (nx,) i1, ``nodes`` (nx,) i8;
                                   attribute ``friction``
``/contact/interfaces/<below>``    ``states``, ``code``, ``lower_nodes``, ``upper_nodes``;
                                   attributes ``friction``, ``below``
``/static`` (when solved)          ``r_n``, ``r_t``, ``gap``, ``slip``, ``held`` (base, as the
                                   static result holds them), ``interfaces/<below>/r_n``...,
                                   ``u`` (n_dofs,); attributes status, success, message,
                                   equilibrium_residual, guarantees, notes...
``/modes``                         ``sigma`` (m,), ``growth_rate`` (m,), ``frequency`` (m,)
                                   (ω = √−σ of a vibration mode), ``residual`` (m,),
                                   ``display_scale`` (m,), ``x`` (m, n_dofs) natural numbering
``/modes/mode_<k>``                ``support`` (base columns, i8), ``interface_support/<below>``;
                                   attributes sigma, growth_rate, residual, display_scale
``/flutter_modes``                 (docs/flutter.md) ``sigma_real``, ``sigma_imag``,
                                   ``growth_rate`` (Re sqrt(sigma)), ``frequency``
                                   (|Im sqrt(sigma)|), ``residual``, ``radius`` (f,),
                                   ``x_real``, ``x_imag`` (f, n_dofs), ``branch``,
                                   ``found_by`` (f,) S;
                                   ``mode_<k>/support``, ``mode_<k>/interface_support/<below>``
``/certificates``                  ``mode_residual`` (m,); attributes ``result_residual``,
                                   ``max_mode_residual``, ``eicp_solves``, ``eicp_method``, ``eicp_status``,
                                   ``eicp_message``, ``eicp_coverage`` (JSON),
                                   ``eicp_outcomes`` (JSON: method, status, message of
                                   each MEiCP, null where every DOF was held)
``/critical_friction`` (when       attributes ``value`` (inf: none found), ``found``, and
computed)                          ``lower``, ``upper``, ``exact``, ``evidence`` as far as
                                   known, ``first`` ("flutter" / "divergence"; absent when
                                   undecided) (:func:`critical_friction_record`); or ``error``
                                   alone: why μ_c was not determined
``/critical_friction/divergence``  attributes ``value``, ``found``, ``lower``, ``upper``,
                                   ``none_at_any_mu``, ``exact``, ``evidence``: the
                                   divergence onset μ_c alone; ``floor`` where its lower end
                                   is about σ = 0 modes alone (no mode of any σ ≥ 0 below it)
``/critical_friction/flutter``     ``lower``, ``upper``, ``none_at_any_mu``, ``exact``,
                                   ``evidence``; ``flutter/mode`` the certified mode at
                                   ``upper`` (``sigma_real``, ``sigma_imag``,
                                   ``growth_rate``, ``frequency``, ``residual``, ``radius``,
                                   ``branch``); no ``flutter`` when not analysed
``/overrides``                     attributes: the solver settings given on the command
                                   line (``method``, ``target``, ``nev``), over the scene's
=================================  ==========================================================

Every dataset carries CF-style ``long_name`` and ``units`` attributes; the model is
dimensionless (``units = "1"``, the numbers in the scene's consistent system: see
:mod:`meicp.io.lattice_output`), and the code datasets carry their legend as
``flag_values`` / ``flag_meanings`` / ``legend``.  Later sections are added as groups
beside ``/modes``; readers ignore what they do not know.

Contact state codes (``/contact/*/code`` and the XDMF field ``contact_state``): 0 not a
contact node, 1 stick, 2 slip+, 3 slip-, 4 separated, 5 grazing, -1 contact node whose state
is unknown.  For a frictional interface both nodes of a column carry its code.

Nothing half-written is ever left: the result is checked first (mode lengths, states, ...),
then every file is written into a hidden staging directory inside the output directory and
moved into place only when all of them are complete; on any error the staging directory is
removed (and the output directory too, when this call created it).  Rank 0 writes; the
other ranks of ``comm`` wait for it and return the same paths, or raise the same error.

Layout: this module holds :func:`write_results` (the staging, the rank-0 logic, lattice.h5
with its XDMF and the PNGs); the constants are in :mod:`meicp.io.results_schema`, the versions,
critical friction record and scene text in :mod:`meicp.io.results_records`, the checks of a
result in :mod:`meicp.io.results_prepare`, the HDF5 writer in :mod:`meicp.io.results_h5`.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import shutil
from pathlib import Path

import numpy as np

from ..core.cleanup import on_interrupt, uninterrupted
from ..core.comm import mpi_comm
from ..core.errors import MeicpError, ProblemError
from ..lattice.assembly import as_model
from ..petsc.stages import stage as log_stage
from ..plotting import lattice as plotting
from ..scene import Scene
from .lattice_output import write_lattice
from .results_h5 import _write_h5
from .results_prepare import _line_forces, _prepare
from .results_records import _scene_text, critical_friction_record, onset_record, scene_to_toml, versions
from .results_schema import (CODE_LEGEND, DESCRIPTIONS, FIELD_DESCRIPTIONS, FILES, FORMAT,
                             FORMAT_VERSION, STATE_CODES, STATE_FLAGS, STATIC_FIELDS)

log = logging.getLogger("meicp")

#: the public names, wherever they are defined
__all__ = ["write_results", "versions", "critical_friction_record", "onset_record", "scene_to_toml",
           "FORMAT", "FORMAT_VERSION", "STATE_CODES", "CODE_LEGEND", "STATE_FLAGS", "DESCRIPTIONS",
           "FIELD_DESCRIPTIONS", "FILES", "STATIC_FIELDS"]


def _flutter_fields(model, modes: list) -> tuple[dict, dict, float]:
    """The XDMF fields of the fastest flutter mode (real and imaginary parts, one display
    scale for both), their attributes, and that scale."""
    if not modes:
        return {}, {}, 0.0
    m = modes[0]
    scale = plotting.display_scale(model, np.abs(m["x"]))
    sigma = m["sigma"]
    head = (f"fastest flutter mode (sigma = {sigma.real:.10g} {sigma.imag:+.6g}i, growth rate "
            f"{m['mode'].growth_rate:.6g}) times its display scale {scale:.6g}")
    fields = {"flutter_0_real": scale * m["x"].real, "flutter_0_imag": scale * m["x"].imag}
    attrs = {"flutter_0_real": {"long_name": f"real part of the {head}"},
             "flutter_0_imag": {"long_name": f"imaginary part (a quarter period later) of the {head}"}}
    return fields, attrs, scale


# --------------------------------------------------------------------------- the whole set

def _write_all(stage: Path, scene: Scene, result, prep: dict, text: str, vers: dict, ranks: int,
               max_xdmf_modes: int, plots: bool, mu_c=None, overrides=None) -> dict:
    import h5py

    model = as_model(scene)
    modes = prep["modes"]
    scales = [plotting.display_scale(model, m["x"]) for m in modes]
    written = {}

    _write_h5(h5py, stage / FILES["results"], scene, result, prep, text, vers, scales, ranks, mu_c, overrides)
    written["results"] = FILES["results"]

    fields = {f"mode_{k}": scales[k] * m["x"] for k, m in enumerate(modes[:max_xdmf_modes])}
    described = {f"mode_{k}": {"long_name": f"shape of mode {k} (sigma = {m['sigma']:.10g}) times its display "
                                            f"scale {scales[k]:.6g}"} for k, m in enumerate(modes[:max_xdmf_modes])}
    flutter_fields, flutter_attrs, flutter_scale = _flutter_fields(model, prep["flutter_modes"])
    fields.update(flutter_fields)
    described.update(flutter_attrs)
    fields["contact_state"] = prep["code"]
    if prep["static_u"] is not None:
        fields["static_u"] = prep["static_u"]
    fields.update(prep["node_forces"])
    described.update(FIELD_DESCRIPTIONS)
    files = write_lattice(stage / FILES["lattice"], model, fields=fields, comm=None, scene_text=text,
                          field_attrs=described)
    written["lattice"], written["xdmf"] = files.h5.name, files.xdmf.name

    if plots:
        fastest = modes[0]["mode"] if modes else None
        # mode.png is about divergence: "stable" there means no divergence mode (flutter has its PNG)
        divergence = getattr(result, "divergence", None)
        no_divergence = getattr(result, "stable", None) if divergence is None else divergence is False
        _picture(written, "mode_png", lambda path: plotting.plot_mode(
            model, path, fastest, stable=no_divergence, n_modes=len(modes)), stage)
        if prep["flutter_modes"]:
            m = prep["flutter_modes"][0]
            shape = dataclasses.replace(m["mode"], x=m["x"].real)
            _picture(written, "flutter_png", lambda path: plotting.plot_mode(model, path, shape, heading=(
                f"fastest flutter mode (real part of x), σ = {m['sigma'].real:.6g} {m['sigma'].imag:+.4g}i, "
                f"growth rate {shape.growth_rate:.4g}, frequency {shape.frequency:.4g}"),
                n_modes=len(prep["flutter_modes"])), stage)
        if prep["lines"]:
            per_line = _line_forces(prep, scene.nx)
            u = prep["static_u"]
            u_scale = float(np.abs(u).max()) if u is not None and u.size else None
            lines = []
            for key, label, mu, _, _ in prep["lines"]:
                if fastest is None:
                    sup = None
                elif key == "base":
                    sup = modes[0]["support"]
                else:
                    sup = modes[0]["interface_support"].get(key)
                lines.append(plotting.ContactLine(label=label, friction=mu, states=prep["states"].get(key) or None,
                                         support=sup, scale=u_scale, **per_line[key]))
            _picture(written, "contacts_png", lambda path: plotting.plot_contacts(model, path, lines), stage)
    return written


def _picture(written: dict, key: str, draw, stage: Path) -> None:
    """Draw one PNG into the staging directory.  A picture is an extra: when Matplotlib
    cannot draw it the results are written all the same, without it, and a warning says why
    (the numbers are in results.h5 and lattice.h5)."""
    try:
        draw(stage / FILES[key])
    except Exception as exc:  # noqa: BLE001 - whatever Matplotlib raises, the verdict's files stand
        log.warning("%s not written: %s: %s", FILES[key], type(exc).__name__, exc)
        (stage / FILES[key]).unlink(missing_ok=True)
        return
    written[key] = FILES[key]


def write_results(directory, scene, result, *, comm=None, scene_text: str | None = None,
                  max_xdmf_modes: int = 16, plots: bool = True, critical_friction=None,
                  overrides: dict | None = None) -> dict:
    """Write the outputs of an instability analysis to ``directory`` (created if missing).

    ``scene``: the :class:`Scene` analysed; ``result``: its
    :class:`~meicp.contact.result.InstabilityResult` (modes as NumPy arrays in natural
    numbering, the same on every rank).  ``scene_text``: the scene file's text (default: read
    from ``scene.source``, else regenerated).  ``max_xdmf_modes``: how many modes become
    XDMF fields (all of them go to ``results.h5``).  ``plots``: write the PNGs.
    ``critical_friction``: μ_c when computed (a float, a float carrying its bracket, or its
    :func:`critical_friction_record`), stored in ``/critical_friction``.  ``overrides``: the
    solver settings the command line gave over the scene's, stored in ``/overrides``.

    Returns ``{"results", "lattice", "xdmf", "mode_png", "contacts_png"}`` → Path (the PNG
    keys only when written).  Collective on ``comm``: rank 0 writes, every rank returns the
    same dict or raises the same error.  Raises :class:`ProblemError` for a result that does
    not fit the scene, before anything is written.
    """
    mcomm = mpi_comm(comm)
    rank, size = (0, 1) if mcomm is None else (mcomm.Get_rank(), mcomm.Get_size())
    directory = Path(directory)
    vers = versions()  # on every rank: importing PETSc may be collective
    outcome = None  # (written names) or (error class name, message)
    error = None
    if rank == 0:
        try:
            with log_stage("write"):
                outcome = ("ok", _write_rank0(directory, scene, result, scene_text, vers, size,
                                              max_xdmf_modes, plots, critical_friction, overrides))
        except BaseException as exc:  # noqa: BLE001 - re-raised below, after telling the others
            error = exc
            outcome = ("ProblemError" if isinstance(exc, ProblemError) else "error",
                       f"{exc}" if isinstance(exc, MeicpError) else f"{type(exc).__name__}: {exc}")
    if mcomm is not None:
        outcome = mcomm.bcast(outcome, root=0)
    if error is not None:
        raise error
    kind, payload = outcome
    if kind == "ProblemError":
        raise ProblemError(payload)
    if kind != "ok":
        raise MeicpError(f"writing the results on rank 0 failed: {payload}")
    return {key: directory / name for key, name in payload.items()}


def _write_rank0(directory: Path, scene, result, scene_text, vers, ranks, max_xdmf_modes, plots,
                 mu_c=None, overrides=None) -> dict:
    prep = _prepare(scene, result)  # every check before the disk is touched
    text = _scene_text(scene, scene_text)
    created = None  # the topmost directory this call creates, removed again on error
    for d in [directory, *directory.parents]:
        if d.exists():
            break
        created = d
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ProblemError(f"cannot create output directory {str(directory)!r}: "
                           f"{exc.strerror or exc}") from None
    if not os.access(directory, os.W_OK):
        raise ProblemError(f"output directory {str(directory)!r} is not writable")
    stage = directory / f".meicp-results.{os.getpid()}.tmp"
    moved = False

    def discard():  # on an error, or from the signal watchdog (meicp.core.cleanup)
        shutil.rmtree(stage, ignore_errors=True)
        if created is not None and not moved:
            shutil.rmtree(created, ignore_errors=True)

    try:
        with on_interrupt(discard):
            stage.mkdir()
            written = _write_all(stage, scene, result, prep, text, vers, ranks, max_xdmf_modes, plots, mu_c,
                                 overrides)
            # data first, the XDMF (which points at lattice.h5) after it, results.h5 last; a
            # signal waits for these renames, so the outputs are never half old, half new
            order = [k for k in ("lattice", "xdmf", "mode_png", "flutter_png", "contacts_png", "results")
                     if k in written]
            # a rename that would fail (a directory of that name) must fail before the first one:
            # the files moved already would be new beside old ones
            blocked = [written[k] for k in order if (directory / written[k]).is_dir()]
            if blocked:
                raise ProblemError(f"cannot write {', '.join(blocked)} into {str(directory)!r}: a directory of that "
                                   "name is in the way (nothing was replaced)")
            with uninterrupted():
                for key in order:
                    os.replace(stage / written[key], directory / written[key])
                moved = True
        if plots:  # a stale PNG from an earlier run of another scene would mislead
            for key in ("mode_png", "flutter_png", "contacts_png"):  # not drawn this time (no flutter mode; failed)
                if key not in written and (directory / FILES[key]).exists():
                    (directory / FILES[key]).unlink()
        return written
    except BaseException:
        discard()
        raise
    finally:
        shutil.rmtree(stage, ignore_errors=True)
