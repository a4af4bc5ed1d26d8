# Sources of core/lowrank (one .h/.cpp pair per concept).
