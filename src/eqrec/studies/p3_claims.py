"""Reasons of the P3 claims."""

from __future__ import annotations

from eqrec.studies.claim_reasons import registry

REASONS, reason = registry()
