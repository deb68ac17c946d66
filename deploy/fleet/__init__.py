"""``zendock fleet``: several robots patrolling one room and sharing its docks, run and measured."""
