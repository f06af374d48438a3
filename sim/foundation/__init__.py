"""The foundation: what every floor of `sim` stands on, and `league` may use too.

Ids, atomic writes, the data home, names (plain, and checked for confusables), remedies
(errors that say what to do), counted words and strict YAML. Nothing here imports any
other module of the project, so anything may import it."""
