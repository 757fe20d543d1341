"""Reasons of the P4 claims."""

from __future__ import annotations

from eqrec.studies.claim_reasons import registry

REASONS, reason = registry()
