# Sources of core/scene (one .h/.cpp pair per concept).
