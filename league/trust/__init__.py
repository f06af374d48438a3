"""Results a league can trust: every shared record is signed, and a roster says whose
signature counts for what.

- keys.py: this machine's Ed25519 signing key (made on first use, owner-only file).
- seals.py: the signature over one record (kind, id, version, content hash) and its check.
- roster.py: the league's `roster` table read as who is organiser, which key belongs to
  which racer, which keys are retired or revoked; and the rule that decides whether a
  pulled record's signer may have made it.
- membership.py: what a racer or organiser does to the roster (found the league,
  propose a key, admit, retire, revoke).
- replay.py: a race raced again here from what it names; one whose laps differ is withdrawn.
- standing.py: each result's standing here (replayed, verifiable, unverifiable), which
  boards show and a night's `verification` rule ranks by.

Sync calls into this package: a push seals what it sends (league.sync.sealing), a pull
verifies every seal and holds back records the roster does not allow (league.sync.incoming).
"""
