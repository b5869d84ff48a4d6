# Reference values for tests/analysis/anova_test.cpp, from R's aov(), summary(),
# TukeyHSD(), ptukey() and pf(). The tests hold the printed numbers as literals and do
# not need R. Produced with R 4.2.2:
#   Rscript tests/analysis/anova_reference.R
# Every number is printed with %.17g (round-trip exact).

f <- function(x) paste(sprintf("%.17g", x), collapse = ", ")

# An accurate studentized-range quantile: R's qtukey() stops its secant iteration when
# two iterates differ by < 1e-4, which leaves errors near 1e-8 relative; this solves
# ptukey(q) = p to the last digits instead.
qtukey_accurate <- function(p, k, df) {
  uniroot(function(x) ptukey(x, k, df) - p, c(0.01, 200), tol = 1e-15)$root
}

# summary(aov()) table plus partial eta squared SS / (SS + SS_error).
anova_rows <- function(fit) {
  s <- summary(fit)[[1]]
  res <- nrow(s)
  for (r in seq_len(nrow(s))) {
    eta <- if (r < res) s[["Sum Sq"]][r] / (s[["Sum Sq"]][r] + s[["Sum Sq"]][res]) else NA
    cat(sprintf("  {\"%s\", %d, %s, %s, %s, %s, %s},\n", trimws(rownames(s)[r]), s$Df[r],
                f(s[["Sum Sq"]][r]), f(s[["Mean Sq"]][r]), f(s[["F value"]][r]),
                f(s[["Pr(>F)"]][r]), f(eta)))
  }
}

# TukeyHSD rows with R's own bounds and the bounds from the accurate quantile.
tukey_rows <- function(fit, which, k) {
  t <- TukeyHSD(fit, which)[[which]]
  q_r <- qtukey(0.95, k, fit$df.residual)
  q_a <- qtukey_accurate(0.95, k, fit$df.residual)
  for (r in seq_len(nrow(t))) {
    half <- (t[r, "upr"] - t[r, "diff"]) / q_r  # standard error of the difference
    cat(sprintf("  {\"%s\", %s, %s, %s, %s, %s, %s},\n", rownames(t)[r], f(t[r, "diff"]),
                f(t[r, "lwr"]), f(t[r, "upr"]), f(t[r, "p adj"]),
                f(t[r, "diff"] - q_a * half), f(t[r, "diff"] + q_a * half)))
  }
}

cat("== warpbreaks: aov(breaks ~ wool * tension) ==\n")
fit <- aov(breaks ~ wool * tension, data = warpbreaks)
anova_rows(fit)
cat("-- TukeyHSD tension --\n"); tukey_rows(fit, "tension", 3)
cat("-- TukeyHSD wool --\n"); tukey_rows(fit, "wool", 2)
cat("-- describe by tension: mean, var, sd --\n")
for (l in levels(warpbreaks$tension)) {
  y <- warpbreaks$breaks[warpbreaks$tension == l]
  cat(sprintf("  {\"%s\", %s, %s, %s},\n", l, f(mean(y)), f(var(y)), f(sd(y))))
}

cat("== npk: aov(yield ~ N * block) ==\n")
fit <- aov(yield ~ N * block, data = npk)
anova_rows(fit)
cat("-- TukeyHSD block --\n"); tukey_rows(fit, "block", 6)

cat("== sleep: aov(extra ~ group + ID) (no replicates) ==\n")
fit <- aov(extra ~ group + ID, data = sleep)
anova_rows(fit)
cat("-- TukeyHSD group --\n"); tukey_rows(fit, "group", 2)

cat("== random 1: 4 modes x 6 subjects, no replicates ==\n")
set.seed(20261121)
d1 <- expand.grid(subject = paste0("S", 1:6), mode = c("BASIC", "PCONTROL", "ALPHA", "NONE"))
d1$y <- round(rnorm(24, mean = 10, sd = 2) + rep(c(0, 1, 2, 0.5), each = 6), 3)
cat("y:", f(d1$y), "\n")
fit <- aov(y ~ mode + subject, data = d1)
anova_rows(fit)
cat("-- TukeyHSD mode --\n"); tukey_rows(fit, "mode", 4)
cat("-- inter-subject variance per mode --\n")
for (l in levels(d1$mode)) cat(sprintf("  {\"%s\", %s},\n", l, f(var(d1$y[d1$mode == l]))))

cat("== random 2: 3 modes x 4 subjects x 3 replicates ==\n")
set.seed(7)
d2 <- expand.grid(rep = 1:3, subject = paste0("S", 1:4), mode = c("BASIC", "PCONTROL", "ALPHA"))
d2$y <- round(5 + rep(c(0, 0.8, 1.5), each = 12) + rep(rnorm(4, 0, 0.7), each = 3, times = 3) +
              rnorm(36, 0, 1), 3)
cat("y:", f(d2$y), "\n")
fit <- aov(y ~ mode * subject, data = d2)
anova_rows(fit)
cat("-- TukeyHSD mode (fixed) --\n"); tukey_rows(fit, "mode", 3)
cat("-- mixed model, subject random: mode tested against mode:subject --\n")
s <- summary(fit)[[1]]
f_mode <- s[["Mean Sq"]][1] / s[["Mean Sq"]][3]
cat(sprintf("  F %s p %s eta %s\n", f(f_mode),
            f(pf(f_mode, s$Df[1], s$Df[3], lower.tail = FALSE)),
            f(s[["Sum Sq"]][1] / (s[["Sum Sq"]][1] + s[["Sum Sq"]][3]))))
cat("-- Tukey for mode against mode:subject (TukeyHSD's formulas, MS and df of mode:subject) --\n")
means <- tapply(d2$y, d2$mode, mean)
se <- sqrt(s[["Mean Sq"]][3] / 2 * (2 / 12))
q_a <- qtukey_accurate(0.95, 3, s$Df[3])
for (j in 2:3) for (i in 1:(j - 1)) {
  d <- means[[j]] - means[[i]]
  cat(sprintf("  {\"%s-%s\", %s, %s, %s, %s},\n", names(means)[j], names(means)[i], f(d),
              f(d - q_a * se), f(d + q_a * se),
              f(ptukey(abs(d) / se, 3, s$Df[3], lower.tail = FALSE))))
}
cat("-- inter-subject variance per mode (variance of the subject means) --\n")
cm <- tapply(d2$y, list(d2$mode, d2$subject), mean)
for (l in rownames(cm)) cat(sprintf("  {\"%s\", %s},\n", l, f(var(cm[l, ]))))

cat("== ptukey(q, k, df) ==\n")
for (k in c(2, 3, 5, 10, 20)) for (df in c(2, 5, 12, 48, 200, 1000, 30000, Inf)) for (q in c(0.5, 2.5, 4, 7)) {
  cat(sprintf("  {%s, %d, %s, %s, %s},\n", f(q), k, f(df), f(ptukey(q, k, df)),
              f(ptukey(q, k, df, lower.tail = FALSE))))
}
cat("== accurate quantile, and R's qtukey ==\n")
for (p in c(0.5, 0.9, 0.95, 0.99)) for (k in c(2, 3, 6, 10)) for (df in c(2, 7, 48, 1000)) {
  cat(sprintf("  {%s, %d, %s, %s, %s},\n", f(p), k, f(df), f(qtukey_accurate(p, k, df)),
              f(qtukey(p, k, df))))
}

# One-way ANOVA and Tukey HSD (oneWayAnova, tukeyHsdOneWay): PlantGrowth, whole and with
# rows 1, 2 and 11 left out (unequal groups: the Tukey–Kramer standard error).
for (d in list(PlantGrowth, PlantGrowth[-c(1, 2, 11), ])) {
  fit <- aov(weight ~ group, data = d)
  s <- summary(fit)[[1]]
  cat("oneway: SS", f(s[["Sum Sq"]]), "F", f(s[["F value"]][1]), "p", f(s[["Pr(>F)"]][1]), "\n")
  t <- TukeyHSD(fit)$group
  cat("tukey:", rownames(t), "\n diff", f(t[, 1]), "\n lwr", f(t[, 2]), "\n upr", f(t[, 3]), "\n p", f(t[, 4]), "\n")
}
