"""Time trials under league rules: the rules, the race engine and race results."""
