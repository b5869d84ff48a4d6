# Data sets and reference values for tests/analysis/lmm_test.cpp, from lme4's lmer() and
# lmerTest's summary() (Satterthwaite) and anova() (type III), and lme4's anova() between
# models (likelihood-ratio tests, refitted by ML). The tests hold the printed numbers as
# literals and read the data sets from tests/analysis/lmm_reference/; they do not need R.
# Produced with R 4.2.2, lme4 1.1.31, lmerTest 3.1.3:
#   cd tests/analysis && LC_ALL=C Rscript lmm_reference.R
# Every fit is made with a tight optimizer tolerance, so the values are lme4's optimum,
# not where its default stopping rule happens to leave it.
suppressMessages(library(lmerTest))
tight <- lmerControl(optimizer = "nloptwrap",
                     optCtrl = list(xtol_abs = 1e-13, ftol_abs = 1e-15, xtol_rel = 0, maxeval = 1e5),
                     check.conv.singular = "ignore")
f <- function(x) paste(sprintf("%.17g", x), collapse = ", ")
dir.create("lmm_reference", showWarnings = FALSE)

# Writes one fit as C++ initializers: coefficients, term tests, variance components.
print_fit <- function(name, data, formula, reml = TRUE) {
  m <- lmer(as.formula(formula), data = data, REML = reml, control = tight)
  s <- summary(m)$coefficients
  cat(sprintf("// %s: %s (%s)\n", name, formula, if (reml) "REML" else "ML"))
  cat(sprintf("const LmmReference k%s{\"%s\", \"%s\", %s,\n", name, name, formula, if (reml) "true" else "false"))
  cat(sprintf("  /*criterion*/ %s, /*sigma*/ %s, /*aic*/ %s, /*bic*/ %s,\n", f(-2 * as.numeric(logLik(m))),
              f(sigma(m)), f(AIC(m)), f(BIC(m))))
  cat("  {\n")
  for (r in seq_len(nrow(s))) {
    cat(sprintf("    {\"%s\", %s, %s, %s, %s},\n", rownames(s)[r], f(s[r, "Estimate"]), f(s[r, "Std. Error"]),
                f(s[r, "df"]), f(s[r, "Pr(>|t|)"])))
  }
  cat("  },\n  {\n")
  a <- anova(m, type = 3)
  for (r in seq_len(nrow(a))) {
    cat(sprintf("    {\"%s\", %s, %s, %s, %s},\n", rownames(a)[r], f(a[r, "NumDF"]), f(a[r, "DenDF"]),
                f(a[r, "F value"]), f(a[r, "Pr(>F)"])))
  }
  cat("  },\n  {\n")
  vc <- as.data.frame(VarCorr(m))
  for (r in seq_len(nrow(vc))) {
    cat(sprintf("    {\"%s\", \"%s\", \"%s\", %s},\n", vc$grp[r], ifelse(is.na(vc$var1[r]), "", vc$var1[r]),
                ifelse(is.na(vc$var2[r]), "", vc$var2[r]), f(vc$sdcor[r])))
  }
  cat(sprintf("  },\n  /*singular*/ %s};\n\n", if (isSingular(m)) "true" else "false"))
  invisible(m)
}

# 1. Modes within subjects over trials, random intercepts and slopes; 14 trials missing.
set.seed(37)
d1 <- expand.grid(trial = 1:8, mode = c("ALPHA", "BASIC", "PCONTROL"), subject = sprintf("s%02d", 1:10),
                  stringsAsFactors = FALSE)
u0 <- rnorm(10, 0, 2); u1 <- rnorm(10, 0, 0.3)
si <- match(d1$subject, sprintf("s%02d", 1:10))
d1$cost <- round(20 + c(ALPHA = -2, BASIC = 0, PCONTROL = -1)[d1$mode] + u0[si] +
                 (-0.5 + u1[si] + c(ALPHA = -0.2, BASIC = 0, PCONTROL = -0.1)[d1$mode]) * d1$trial +
                 rnorm(nrow(d1), 0, 1.5), 3)
d1 <- d1[-sample(nrow(d1), 14), c("subject", "mode", "trial", "cost")]
write.csv(d1, "lmm_reference/slopes.csv", row.names = FALSE, quote = FALSE)

# 2. Groups between subjects, crossed subjects and items (characters); missing trials.
set.seed(38)
d2 <- expand.grid(item = sprintf("c%d", 1:6), subject = sprintf("p%02d", 1:12), stringsAsFactors = FALSE)
d2$group <- c("fading", "guided", "free")[(match(d2$subject, sprintf("p%02d", 1:12)) - 1) %% 3 + 1]
d2$score <- round(5 + c(fading = -0.8, guided = -0.3, free = 0)[d2$group] +
                  rnorm(12, 0, 0.7)[match(d2$subject, sprintf("p%02d", 1:12))] +
                  rnorm(6, 0, 0.5)[match(d2$item, sprintf("c%d", 1:6))] + rnorm(nrow(d2), 0, 0.6), 3)
d2 <- d2[-sample(nrow(d2), 9), c("subject", "item", "group", "score")]
write.csv(d2, "lmm_reference/crossed.csv", row.names = FALSE, quote = FALSE)

# 3. Classes nested in schools, a factor-by-factor interaction with a missing cell.
set.seed(39)
d3 <- expand.grid(rep = 1:4, class = c("a", "b", "c"), school = c("north", "south", "east", "west", "centre", "hill"),
                  hand = c("left", "right"), stringsAsFactors = FALSE)
d3$plan <- ifelse(d3$school %in% c("north", "east", "hill"), "daily", "weekly")
d3$speed <- round(30 + 3 * (d3$plan == "weekly") + 2 * (d3$hand == "left") +
                  rnorm(6, 0, 2.5)[match(d3$school, c("north", "south", "east", "west", "centre", "hill"))] +
                  rnorm(18, 0, 1.5)[match(paste(d3$school, d3$class), unique(paste(d3$school, d3$class)))] +
                  rnorm(nrow(d3), 0, 2), 2)
d3 <- d3[!(d3$plan == "weekly" & d3$hand == "left" & d3$rep > 2), c("school", "class", "hand", "plan", "speed")]
write.csv(d3, "lmm_reference/nested.csv", row.names = FALSE, quote = FALSE)

print_fit("Slopes", d1, "cost ~ mode * trial + (1 + trial | subject)")
print_fit("SlopesMl", d1, "cost ~ mode * trial + (1 + trial | subject)", reml = FALSE)
print_fit("Crossed", d2, "score ~ group + (1 | subject) + (1 | item)")
print_fit("Nested", d3, "speed ~ plan * hand + (1 | school/class)")
print_fit("Independent", d1, "cost ~ mode + trial + (1 + trial || subject)")

# Likelihood-ratio tests between nested models, as lme4's anova() gives them (ML refits).
m0 <- lmer(cost ~ trial + (1 + trial | subject), data = d1, REML = FALSE, control = tight)
m1 <- lmer(cost ~ mode + trial + (1 + trial | subject), data = d1, REML = FALSE, control = tight)
a <- anova(m0, m1)
cat(sprintf("// LRT mode: chisq %s, df %s, p %s\n", f(a$Chisq[2]), f(a$Df[2]), f(a[["Pr(>Chisq)"]][2])))

# 4. A singular fit: no subject variance in the data at all.
set.seed(40)
d4 <- expand.grid(trial = 1:5, subject = sprintf("q%d", 1:6), stringsAsFactors = FALSE)
d4$time <- round(3 - 0.1 * d4$trial + rnorm(nrow(d4), 0, 0.4), 3)
write.csv(d4[, c("subject", "trial", "time")], "lmm_reference/singular.csv", row.names = FALSE, quote = FALSE)
print_fit("Singular", d4, "time ~ trial + (1 | subject)")

# 5. An empty cell: no weekly plan with a left hand. lme4 drops the dependent column
# (planweekly:handright) and lmerTest tests what remains.
d5 <- d3[!(d3$plan == "weekly" & d3$hand == "left"), ]
write.csv(d5, "lmm_reference/empty_cell.csv", row.names = FALSE, quote = FALSE)
print_fit("EmptyCell", d5, "speed ~ plan * hand + (1 | school)")

# 6. R's conventions beyond the usual formula: type III tests of terms without their margins,
# models without an intercept, interactions named in the fixed part's order, lme4's order
# of groupings, and a column that is both a covariate and a grouping.
set.seed(41)
d6 <- data.frame(g = rep(sprintf("g%d", 1:6), each = 10), h = rep(sprintf("h%02d", 1:15), times = 4),
                 a = rep(c("A", "B", "C"), 20), b = rep(rep(c("p", "q"), each = 3), 10),
                 x = round(runif(60, 0, 4), 2), s = rep(1:6, times = 10), stringsAsFactors = FALSE)
d6$y <- round(3 + 0.5 * d6$x + c(A = 0, B = 1, C = -0.5)[d6$a] * (1 + 0.3 * d6$x) + 0.8 * (d6$b == "q") +
              0.1 * d6$s + rnorm(6, 0, 1)[match(d6$g, sprintf("g%d", 1:6))] +
              rnorm(15, 0, 0.5)[match(d6$h, sprintf("h%02d", 1:15))] +
              rnorm(6, 0, 0.4)[d6$s] + rnorm(60, 0, 0.7), 3)
write.csv(d6, "lmm_reference/conventions.csv", row.names = FALSE, quote = FALSE)
print_fit("SlopeWithoutMargin", d6, "y ~ x + x:a + (1 | g)")
print_fit("NestedFactor", d6, "y ~ a + a:b + (1 | g)")
print_fit("NoIntercept", d6, "y ~ 0 + a + b + (1 | g)")
print_fit("NoInterceptSlopes", d6, "y ~ 0 + x + x:a + (1 | g)")
print_fit("Margins", d6, "y ~ x:a + x:b + (1 | g)")
print_fit("FixedOrder", d6, "y ~ (1 + x | g) + a * x")
print_fit("GroupOrder", d6, "y ~ x + (1 + x || g) + (1 | h)")
print_fit("CovariateAndGroup", d6, "y ~ s + (1 | s) + (1 | h)")
print_fit("MinusOne", d6, "y ~ -1 + x + b + (x - 1 | g)")
